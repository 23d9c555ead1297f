"""Monte Carlo localization in one call: the numbers of `implicit mcl --json`.

Example::

    import implicit
    r = implicit.mcl.run(method="implicit", particles=100, runs=2, seed=1)
    r["rmse_m"], r["error_percent_mean"]

For stepping a filter yourself see implicit.ParticleFilter.
"""
from . import _implicit, _runs


def run(method="implicit", particles=100, runs=20, seed=1, data=None, config="A", p=None,
        q=None, map="linear", clutter=True, sigma2="variance", truth="gps", gps_std=0.5,
        reference_particles=5000, model=None, control_sd=None, state_sd=None, range_sd=0.0,
        bearing_sd_deg=0.0, out=None, threads=0, init="known", start_span=60.0, duration=0.0,
        kidnap_at=None, kidnap_skip=10.0, recovery="auto", recovery_alpha_slow=0.001,
        recovery_alpha_fast=0.1, kidnap_probability=1e-3, kld=False, kld_err=0.01, kld_z=0.99,
        min_particles=100, max_particles=5000, cover_spacing=2.0, cover_headings=8,
        label_gate=27.631021115928547, verbose=False, bearing_sd=None, progress=None):
    """Runs `implicit mcl` with these settings and returns its JSON result as a dict.

    Each argument is the CLI flag of the same name (docs/cli.md): method "standard"
    (bootstrap) or "implicit"; particles M; runs with seeds seed * runs + r; data a Car Park
    folder or robot log (None: the bundled Car Park data); config "A" (P = 0.5) or "B" (P =
    0.1); p, q noise overrides; map "linear" or "random"; range_sd [m] and bearing_sd_deg [deg]
    (--range-sd, --bearing-sd; bearing_sd, the same in degrees, is deprecated); out a folder
    for the CSV files (None: none written); threads 0 = all cores; model a motion model by name
    (None: the one the log declares; implicit.models.motion_models() lists them, and
    implicit.models.register_motion_model adds your own). Localization without a known
    start (user guide §9, spec §3.11): init "known" or "global", start_span and duration [s],
    kidnap_at [s] (None: no kidnapping) and kidnap_skip [s], recovery "auto", "none", "uniform"
    or "mixture" with recovery_alpha_slow, recovery_alpha_fast and kidnap_probability, kld with
    kld_err, kld_z, min_particles and max_particles, and the multi-start's cover_spacing [m] and
    cover_headings. label_gate: labelled detections whose d^2 against the predicted pose exceeds
    it are left out and counted ("labelled_gated"); 0 trusts every label. verbose: True draws
    the tool's progress bar (runs done, ETA) on stderr, as `implicit mcl` without --json does;
    the result is the same either way. progress, if given, is called as progress(runs done,
    runs in all) after runs finish, with the interpreter's lock held, at most about 10 times a
    second and once more with done = total at the end; done never decreases. An exception it
    raises stops the run (with several threads too: the runs under way finish, no other starts)
    and reaches the caller unchanged. The result is the same with or without it.

    Returns:
        dict with the keys of `implicit mcl --json` (position_rmse_m [m] (alias rmse_m),
        error_percent_mean, heading_rmse_rad, ess_mean, resamplings_mean, cpu_ms_per_step,
        lost_runs, ...; a global or kidnapping run:
        global_success_rate or kidnap_recovery_rate, the median times, particles_mean, ...), the
        same numbers for the same seed. Timing keys differ from run to run.

    Raises:
        implicit.InvalidArgument (a ValueError) naming the keyword, for a value the CLI refuses:
        each number is checked against the range of its flag (`p` in [0, 10], `particles` in
        [1, 10^7], `threads` in [0, 1024], ...; `implicit mcl --help` lists them), a wrong type
        (a str for a number, a float for a count) likewise; the text settings (method, config,
        ...) with the CLI's own message.
    """
    settings = dict(
        method=method, particles=particles, runs=runs, data=data, config=config, p=p, q=q,
        map=map, clutter=clutter, sigma2=sigma2, truth=truth, gps_std=gps_std,
        reference_particles=reference_particles, model=model, control_sd=control_sd,
        state_sd=state_sd, range_sd=range_sd,
        bearing_sd_deg=_runs.bearing_sd_deg(bearing_sd_deg, bearing_sd, "mcl.run"), init=init,
        start_span=start_span, duration=duration, kidnap_at=kidnap_at, kidnap_skip=kidnap_skip,
        recovery=recovery, recovery_alpha_slow=recovery_alpha_slow,
        recovery_alpha_fast=recovery_alpha_fast, kidnap_probability=kidnap_probability, kld=kld,
        kld_err=kld_err, kld_z=kld_z, min_particles=min_particles, max_particles=max_particles,
        cover_spacing=cover_spacing, cover_headings=cover_headings, label_gate=label_gate)
    return _runs.call(_implicit._run_mcl, settings, seed, out, threads, verbose,
                      given_as=None if bearing_sd is None else {"bearing_sd_deg": "bearing_sd"},
                      progress=progress)
