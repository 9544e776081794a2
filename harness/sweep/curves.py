"""IDA and fragility curves from a sweep's rows.

- IDA (incremental dynamic analysis): at each PGA level, the median and the 16th and 84th
  percentiles of a peak response over the records and samples, per design and for the
  passive case.
- Fragility: at each PGA level, the share of cases whose peak exceeds a limit, per design,
  with a lognormal fit ``P(exceed | PGA = x) = Phi(ln(x / theta) / beta)`` by maximum
  likelihood on the binomial counts (Baker 2015, "Efficient analytical fragility function
  fitting using dynamic structural analysis"): ``theta`` is the median PGA at which the
  limit is exceeded (g), ``beta`` the logarithmic standard deviation. A fit the counts cannot
  support is kept but marked (:func:`fit_warning`): a step (no level where some but not all
  cases exceed: ``beta`` is then whatever the optimizer stops at, and ``theta`` anywhere
  between two levels fits) or fewer than :data:`MIN_CASES_PER_LEVEL` cases at a level.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from harness.sweep.summary import groups, ok_rows, passive_rows

Columns = Mapping[str, np.ndarray]
PASSIVE_DESIGN = "passive"
#: Fewest cases at a PGA level for its share to resolve 10 % of exceedance; with fewer (2 records
#: a level give shares of 0, 0.5 or 1 only) the fitted curve is not meaningful.
MIN_CASES_PER_LEVEL = 10
#: How a note marks a fit the counts do not support.
NOT_MEANINGFUL = "fit not meaningful"


@dataclass(frozen=True)
class IdaCurve:
    """A response against PGA: levels (g) and the median, p16 and p84 at each (SI), with the count."""

    design: str
    pga_g: np.ndarray
    median: np.ndarray
    p16: np.ndarray
    p84: np.ndarray
    count: np.ndarray


@dataclass(frozen=True)
class Fragility:
    """Exceedance of a limit against PGA, with the lognormal fit (NaN where it cannot be fitted)."""

    design: str
    pga_g: np.ndarray
    exceeded: np.ndarray
    count: np.ndarray
    theta_g: float
    beta: float
    note: str = ""

    @property
    def meaningful(self) -> bool:
        """Whether the fit is there and the counts support it (:func:`fit_warning` found nothing)."""
        return bool(np.isfinite(self.theta_g)) and NOT_MEANINGFUL not in self.note

    @property
    def share(self) -> np.ndarray:
        """Observed probability of exceedance at each level."""
        return self.exceeded / np.maximum(self.count, 1)

    def fitted(self, pga_g: np.ndarray) -> np.ndarray:
        """The fitted probability of exceedance at ``pga_g`` (g)."""
        from scipy import stats

        if not np.isfinite(self.theta_g):
            return np.full(np.shape(pga_g), np.nan)
        return np.asarray(stats.norm.cdf(np.log(np.asarray(pga_g) / self.theta_g) / self.beta))


def _levels(pga: np.ndarray) -> np.ndarray:
    return np.unique(pga[np.isfinite(pga)])


def ida_curve(design: str, pga: np.ndarray, response: np.ndarray) -> IdaCurve:
    """Median and 16/84th percentiles of ``response`` at each PGA level of ``pga`` (NaN responses left out)."""
    levels = _levels(pga)
    stats = np.full((len(levels), 3), np.nan)
    counts = np.zeros(len(levels), dtype=int)
    for i, level in enumerate(levels):
        values = response[(pga == level) & np.isfinite(response)]
        counts[i] = values.size
        if values.size:
            stats[i] = np.percentile(values, [50, 16, 84])
    return IdaCurve(design, levels, stats[:, 0], stats[:, 1], stats[:, 2], counts)


def fit_lognormal(pga_g: np.ndarray, exceeded: np.ndarray, count: np.ndarray) -> tuple[float, float, str]:
    """Maximum-likelihood (theta in g, beta) of a lognormal fragility on binomial counts.

    Returns NaN for both, with a note, when the data cannot fix them: fewer than two levels,
    no exceedance at all, or exceedance everywhere.
    """
    from scipy import optimize, stats

    if len(pga_g) < 2:
        return float("nan"), float("nan"), "one PGA level: no fit"
    if exceeded.sum() == 0:
        return float("nan"), float("nan"), "never exceeded"
    if np.all(exceeded == count):
        return float("nan"), float("nan"), "always exceeded"
    log_x = np.log(pga_g)

    def negative_log_likelihood(params: np.ndarray) -> float:
        z = (log_x - params[0]) / np.exp(params[1])
        return -float(np.sum(exceeded * stats.norm.logcdf(z) + (count - exceeded) * stats.norm.logsf(z)))

    share = exceeded / np.maximum(count, 1)
    start = np.array([log_x[np.argmin(np.abs(share - 0.5))], np.log(0.4)])
    best = optimize.minimize(negative_log_likelihood, start, method="Nelder-Mead", options={"xatol": 1e-6, "fatol": 1e-9})
    return float(np.exp(best.x[0])), float(np.exp(best.x[1])), "" if best.success else f"fit: {best.message}"


def fit_warning(exceeded: np.ndarray, count: np.ndarray) -> str:
    """Why a lognormal fit to these counts is not meaningful ("" if it is), for the plot, CSV and summary.

    Parameters
    ----------
    exceeded, count : ndarray of int
        Cases exceeding the limit, and cases, at each PGA level.
    """
    between = (exceeded > 0) & (exceeded < count)
    if not between.any():
        return (f"{NOT_MEANINGFUL}: a step (no PGA level where some but not all cases exceed), so beta is not "
                "determined and theta lies anywhere between two levels")
    if np.min(count) < MIN_CASES_PER_LEVEL:
        return (f"{NOT_MEANINGFUL}: {int(np.min(count))} cases at a level, fewer than {MIN_CASES_PER_LEVEL} "
                "(more records or samples per level)")
    return ""


def fragility(design: str, pga: np.ndarray, response: np.ndarray, limit: float) -> Fragility:
    """Exceedance of ``limit`` by ``response`` at each PGA level, with its lognormal fit."""
    levels = _levels(pga)
    valid = np.isfinite(response)
    count = np.array([np.sum((pga == level) & valid) for level in levels], dtype=int)
    exceeded = np.array([np.sum((pga == level) & valid & (response > limit)) for level in levels], dtype=int)
    theta, beta, note = fit_lognormal(levels, exceeded, count)
    if np.isfinite(theta):
        note = "; ".join(text for text in (note, fit_warning(exceeded, count)) if text)
    return Fragility(design, levels, exceeded, count, theta, beta, note)


def design_curves(columns: Columns, labels: np.ndarray, response: str) -> list[IdaCurve]:
    """IDA curves of ``response`` (a flattened peak name): the passive case, then each design."""
    ok = ok_rows(columns)
    pga = columns["pga_g"]
    passive = passive_rows(columns)
    curves = [ida_curve(PASSIVE_DESIGN, pga[passive], columns[f"passive.{response}"][passive])]
    for design, rows in groups(labels).items():
        chosen = rows[ok[rows]]
        if design.split(",")[0] != "none" and f"controlled.{response}" in columns:
            curves.append(ida_curve(design, pga[chosen], columns[f"controlled.{response}"][chosen]))
    return curves


def design_fragilities(columns: Columns, labels: np.ndarray, response: str, limit: float) -> list[Fragility]:
    """Fragility curves of ``response`` against ``limit``: the passive case, then each design."""
    ok = ok_rows(columns)
    pga = columns["pga_g"]
    passive = passive_rows(columns)
    curves = [fragility(PASSIVE_DESIGN, pga[passive], columns[f"passive.{response}"][passive], limit)]
    for design, rows in groups(labels).items():
        chosen = rows[ok[rows]]
        if design.split(",")[0] != "none" and f"controlled.{response}" in columns:
            curves.append(fragility(design, pga[chosen], columns[f"controlled.{response}"][chosen], limit))
    return curves
