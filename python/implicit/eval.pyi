from typing import Any

import numpy.typing as npt

from ._implicit import InvalidArgument as InvalidArgument

def ape(ref: npt.ArrayLike, est: npt.ArrayLike, align: str = "none", max_diff: float = 0.01,
        offset: float = 0.0, seed: int = 1) -> dict[str, Any]: ...
def rpe(ref: npt.ArrayLike, est: npt.ArrayLike, delta: float = 1, delta_unit: str = "frames",
        all_pairs: bool = False, align: str = "none", max_diff: float = 0.01,
        offset: float = 0.0, seed: int = 1) -> dict[str, Any]: ...
