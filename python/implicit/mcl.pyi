from typing import Any, Callable, Optional, Sequence

def run(method: str = "implicit", particles: int = 100, runs: int = 20, seed: int = 1,
        data: Optional[str] = None, config: str = "A", p: Optional[float] = None,
        q: Optional[float] = None, map: str = "linear", clutter: bool = True,
        sigma2: str = "variance", truth: str = "gps", gps_std: float = 0.5,
        reference_particles: int = 5000, model: Optional[str] = None,
        control_sd: Optional[Sequence[float]] = None,
        state_sd: Optional[Sequence[float]] = None, range_sd: float = 0.0,
        bearing_sd_deg: float = 0.0, out: Optional[str] = None,
        threads: int = 0, init: str = "known", start_span: float = 60.0,
        duration: float = 0.0, kidnap_at: Optional[float] = None, kidnap_skip: float = 10.0,
        recovery: str = "auto", recovery_alpha_slow: float = 0.001,
        recovery_alpha_fast: float = 0.1, kidnap_probability: float = 1e-3, kld: bool = False,
        kld_err: float = 0.01, kld_z: float = 0.99, min_particles: int = 100,
        max_particles: int = 5000, cover_spacing: float = 2.0,
        cover_headings: int = 8, label_gate: float = 27.631021115928547,
        verbose: bool = False, bearing_sd: Optional[float] = None,
        progress: Optional[Callable[[int, int], Any]] = None) -> dict[str, Any]: ...
