"""Shared plumbing of the one-call runners: the tool's experiment code, its JSON as a dict."""
import json
import warnings

from . import _implicit


def call(fn, settings, seed, out, threads, verbose=False, given_as=None, progress=None):
    """Runs an experiment of the command-line tool and returns its JSON result as a dict.

    The settings, seed, out, threads, verbose and progress are passed as given: the compiled side
    checks each against the range of the tool's flag (progress: a callable or None) and names the
    keyword it refuses. given_as maps a setting to the deprecated keyword the caller used for it,
    which a refusal then names."""
    try:
        return json.loads(fn(settings, seed, out, threads, verbose, progress))
    except _implicit.InvalidArgument as e:
        for key, old in (given_as or {}).items():
            if str(e).startswith(key + ":"):
                raise _implicit.InvalidArgument(old + str(e)[len(key):]) from None
        raise


def bearing_sd_deg(new, old, where):
    """The bearing noise in degrees: bearing_sd_deg, or the deprecated keyword bearing_sd (the
    same degrees; its name did not say the unit, while the sensors' bearings are radians)."""
    if old is None:
        return new
    # stacklevel 3: the warning points at the caller of mcl.run / slam.run.
    warnings.warn(f"{where}: bearing_sd is deprecated (its name does not say the unit); pass "
                  "bearing_sd_deg, the same value in degrees", DeprecationWarning, stacklevel=3)
    if new != 0.0:
        raise _implicit.InvalidArgument(
            f"bearing_sd_deg: pass it or the deprecated bearing_sd, not both (got {new!r} and "
            f"{old!r})")
    return old
