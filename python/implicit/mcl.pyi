from typing import Any, Optional, Sequence

def run(method: str = "implicit", particles: int = 100, runs: int = 20, seed: int = 1,
        data: Optional[str] = None, config: str = "A", p: Optional[float] = None,
        q: Optional[float] = None, map: str = "linear", clutter: bool = True,
        sigma2: str = "variance", truth: str = "gps", gps_std: float = 0.5,
        reference_particles: int = 5000, model: Optional[str] = None,
        control_sd: Optional[Sequence[float]] = None,
        state_sd: Optional[Sequence[float]] = None, range_sd: float = 0.0,
        bearing_sd: float = 0.0, out: Optional[str] = None,
        threads: int = 0) -> dict[str, Any]: ...
