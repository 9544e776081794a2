"""Monte-Carlo distributions of a study, and samples of them: Latin hypercube or plain random.

Each distribution maps a uniform number ``u`` in (0, 1) to a value through its inverse CDF
(:meth:`ppf`), so both samplers draw uniform points in the unit hypercube, one dimension per
parameter, and map each column. Distribution parameters are plain numbers in the unit the
profile key names (SI), or factors for a ``scale`` parameter.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from harness.config.schema import quantity


@dataclass(frozen=True)
class Uniform:
    """Uniform between ``low`` and ``high``."""

    kind: Literal["uniform"]
    low: float = quantity(doc="lower bound, in the key's unit (or a factor)")
    high: float = quantity(doc="upper bound, in the key's unit (or a factor)")

    def __post_init__(self) -> None:
        if not self.high > self.low:
            raise ValueError(f"high ({self.high:g}) is not above low ({self.low:g}); expected low < high")

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Values at the probabilities ``u`` in (0, 1)."""
        return self.low + (self.high - self.low) * np.asarray(u, dtype=float)


@dataclass(frozen=True)
class Normal:
    """Normal with ``mean`` and standard deviation ``std``, optionally truncated to [low, high]."""

    kind: Literal["normal"]
    mean: float = quantity(doc="mean, in the key's unit (or a factor)")
    std: float = quantity(gt=0, doc="standard deviation, same unit as the mean")
    low: float | None = quantity(None, doc="truncate below (none: no bound)")
    high: float | None = quantity(None, doc="truncate above (none: no bound)")

    def __post_init__(self) -> None:
        if self.low is not None and self.high is not None and not self.high > self.low:
            raise ValueError(f"high ({self.high:g}) is not above low ({self.low:g}); expected low < high")

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Values at the probabilities ``u`` in (0, 1) (of the truncated distribution when bounded)."""
        from scipy import stats

        a = -math.inf if self.low is None else (self.low - self.mean) / self.std
        b = math.inf if self.high is None else (self.high - self.mean) / self.std
        return np.asarray(stats.truncnorm.ppf(np.asarray(u, dtype=float), a, b, loc=self.mean, scale=self.std))


@dataclass(frozen=True)
class LogNormal:
    """Lognormal with ``median`` and logarithmic standard deviation ``beta``."""

    kind: Literal["lognormal"]
    median: float = quantity(gt=0, doc="median, in the key's unit (or a factor)")
    beta: float = quantity(gt=0, doc="standard deviation of ln(value)")

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Values at the probabilities ``u`` in (0, 1)."""
        from scipy import stats

        return np.asarray(stats.lognorm.ppf(np.asarray(u, dtype=float), self.beta, scale=self.median))


Distribution = Uniform | Normal | LogNormal


def unit_samples(n_samples: int, n_dims: int, seed: int, sampling: str) -> np.ndarray:
    """Points in the open unit hypercube, one row per sample.

    Parameters
    ----------
    n_samples, n_dims : int
        Samples and dimensions (parameters).
    seed : int
        Seed: the same seed gives the same points.
    sampling : {"latin_hypercube", "random"}
        Latin hypercube (``scipy.stats.qmc.LatinHypercube``: each parameter's range cut into
        ``n_samples`` equal-probability strata, one sample in each) or independent uniform draws.

    Returns
    -------
    ndarray, shape (n_samples, n_dims)
    """
    rng = np.random.default_rng(seed)
    if sampling == "latin_hypercube":
        from scipy.stats import qmc

        points = qmc.LatinHypercube(d=n_dims, rng=rng).random(n_samples)
    elif sampling == "random":
        points = rng.random((n_samples, n_dims))
    else:
        raise ValueError(f"found sampling {sampling!r}, expected 'latin_hypercube' or 'random'")
    tiny = np.finfo(float).tiny
    return np.clip(points, tiny, 1.0 - np.finfo(float).eps)  # a 0 would map to -inf through a normal's ppf


def draw(distributions: Sequence[Distribution], n_samples: int, seed: int, sampling: str) -> np.ndarray:
    """Samples of every distribution, one column each.

    Returns
    -------
    ndarray, shape (n_samples, len(distributions))
        Plain floats, the column of distribution j in column j.
    """
    points = unit_samples(n_samples, len(distributions), seed, sampling)
    columns = [distribution.ppf(points[:, j]) for j, distribution in enumerate(distributions)]
    return np.column_stack(columns) if columns else np.empty((n_samples, 0))
