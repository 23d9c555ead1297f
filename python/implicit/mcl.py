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
        bearing_sd=0.0, out=None, threads=0, init="known", start_span=60.0, duration=0.0,
        kidnap_at=None, kidnap_skip=10.0, recovery="auto", recovery_alpha_slow=0.001,
        recovery_alpha_fast=0.1, kidnap_probability=1e-3, kld=False, kld_err=0.01, kld_z=0.99,
        min_particles=100, max_particles=5000, cover_spacing=2.0, cover_headings=8):
    """Runs `implicit mcl` with these settings and returns its JSON result as a dict.

    Each argument is the CLI flag of the same name (docs/cli.md): method "standard"
    (bootstrap) or "implicit"; particles M; runs with seeds seed * runs + r; data a Car Park
    folder or robot log (None: the bundled Car Park data); config "A" (P = 0.5) or "B" (P =
    0.1); p, q noise overrides; map "linear" or "random"; bearing_sd in degrees; out a folder
    for the CSV files (None: none written); threads 0 = all cores. Localization without a known
    start (user guide §9, spec §3.11): init "known" or "global", start_span and duration [s],
    kidnap_at [s] (None: no kidnapping) and kidnap_skip [s], recovery "auto", "none", "uniform"
    or "mixture" with recovery_alpha_slow, recovery_alpha_fast and kidnap_probability, kld with
    kld_err, kld_z, min_particles and max_particles, and the multi-start's cover_spacing [m] and
    cover_headings.

    Returns:
        dict with the keys of `implicit mcl --json` (rmse_m [m], error_percent_mean,
        heading_rmse_rad, ess_mean, cpu_ms_per_step, lost_runs, ...; a global or kidnapping run:
        global_success_rate or kidnap_recovery_rate, the median times, particles_mean, ...), the
        same numbers for the same seed. Timing keys differ from run to run.

    Raises:
        implicit.InvalidArgument with the CLI's message for a bad setting.
    """
    settings = dict(
        method=method, particles=int(particles), runs=int(runs),
        data="" if data is None else str(data), config=config,
        p=-1.0 if p is None else float(p), q=-1.0 if q is None else float(q), map=map,
        clutter=bool(clutter), sigma2=sigma2, truth=truth, gps_std=float(gps_std),
        reference_particles=int(reference_particles), model=model or "",
        control_sd=list(control_sd or []), state_sd=list(state_sd or []),
        range_sd=float(range_sd), bearing_sd_deg=float(bearing_sd), init=init,
        start_span=float(start_span), duration=float(duration),
        kidnap_at=-1.0 if kidnap_at is None else float(kidnap_at), kidnap_skip=float(kidnap_skip),
        recovery=recovery, recovery_alpha_slow=float(recovery_alpha_slow),
        recovery_alpha_fast=float(recovery_alpha_fast),
        kidnap_probability=float(kidnap_probability), kld=bool(kld), kld_err=float(kld_err),
        kld_z=float(kld_z), min_particles=int(min_particles), max_particles=int(max_particles),
        cover_spacing=float(cover_spacing), cover_headings=int(cover_headings))
    return _runs.call(_implicit._run_mcl, settings, seed, out, threads)
