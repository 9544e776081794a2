"""``harness identify bearing RUN [RUN ...]``: the bearings' friction law (Eq. 3-5) from run folders."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from rich.console import Console

from harness import exit_codes
from harness.commands.options import OFFLINE_EXIT_STATUS, add_run_folders, number_in, wrap
from harness.config import input_limits as limits

if TYPE_CHECKING:
    from harness.identification.friction_fit import FrictionFit

#: Corner of the low-pass on the measured and fitted force (Hz).
LOWPASS = limits.NumberRange(1.0, 1000.0, "Hz", low_open=False)

EXAMPLES = """\
examples:
  harness identify bearing logs/<RUN> --out ident/bearing      (a dry run's or a real run's folder)
  harness identify bearing logs/<RUN1> logs/<RUN2> --out ident/bearing     (one fit over both)

DIR gets identified.yaml (the determined bearing.* values, each with its standard error: a
profile overlay), identification.json (every parameter, its standard error and whether the data
determined it, the fit error, the runs with the SHA-256 of their signals.csv, the harness
version) and friction.png (friction against sliding velocity and the hysteresis loop, measured
against fitted).
"""


def add_parser(sub) -> None:
    from harness.identification.choices import LOWPASS_HZ

    parser = sub.add_parser(
        "bearing",
        help="the bearings' friction law (mu_max, mu_delta, a_mu, D_y) from run folders",
        description=wrap(
            "Fit the friction law of Eq. 3-5 (mu_max, mu_delta, a_mu and the yield displacement D_y of the Bouc-Wen "
            "variable; alpha, beta, gamma, eta stay the profile's) to the friction force the base mat's force balance "
            "gives (Eq. 1-2): f = u - k_b x_b - m_b a_b - sum_j m_j a_j, from the load cell, the restraining springs, "
            "the base-mat and floor accelerations and the masses of each run's own profile. The hysteretic variable "
            "is simulated along the measured sliding displacement (fused with the sliding velocity); the fit is "
            "scipy.optimize.least_squares over all runs at once. D_y is corrected for the displacement and velocity "
            "sensors' noise in the fit's input by SIMEX (simulation-extrapolation: noise of the sensors' own size, "
            "estimated from the samples, added and the fit repeated 16 times, its trend extrapolated back to no noise). "
            "The output says which parameters the data "
            "determine and why (a run that never slid gives none). Any run folder works: dry runs, real runs, "
            "simulate's cases. A run without the columns needed is refused (exit 2)."
        ),
        epilog=EXAMPLES + "\n" + OFFLINE_EXIT_STATUS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_run_folders(parser, "identified.yaml, identification.json and friction.png")
    parser.add_argument("--lowpass-hz", type=number_in(LOWPASS), default=LOWPASS_HZ, metavar="HZ",
                        help=f"low-pass corner applied to measured and fitted force alike, {LOWPASS.describe()} "
                        f"(default: {LOWPASS_HZ:g})")
    parser.set_defaults(handler=run)


def simex_line(fit: FrictionFit) -> str:
    """One line: which values are SIMEX-corrected for the sensors' noise, and by how much each moved (a fit with SIMEX)."""
    from harness.identification.friction_fit import SIMEX_CORRECTED

    simex = fit.simex
    assert simex is not None, "called only for a fit that made the SIMEX correction"
    moved = ", ".join(f"{name} {100 * (fit.estimates[name].value / simex.plain[name][0] - 1):+.2f} % (plain fit "
                      f"{simex.plain[name][0]:.4g})" for name in SIMEX_CORRECTED)
    noise = ", ".join(f"{1e6 * sx:.2g} um and {1e3 * sv:.2g} mm/s" for sx, sv in
                      zip(simex.displacement_noise_m, simex.velocity_noise_m_s, strict=True))
    return (f"  SIMEX-corrected for the sensors' noise in the fit's input (estimated from the samples: {noise}); "
            f"moved: {moved}")


def run(args: argparse.Namespace, console: Console) -> int:
    from pathlib import Path

    from harness.identification.bearing import identify_bearing
    from harness.identification.run_signals import IdentificationError
    from harness.model.warmup import warm_up

    warm_up()
    result = identify_bearing(args.runs, Path(args.out), args.lowpass_hz, args.force)
    fit = result.fit
    console.print(f"bearing friction from {len(result.runs)} run(s), {result.building.total_weight_N / 1e3:.4g} kN carried:",
                  highlight=False)
    for estimate in fit.estimates.values():
        mark = "[green]determined[/]" if estimate.determined else "[yellow]not determined[/]"
        console.print(f"  {estimate.name} = {estimate.value:.4g} +/- {estimate.standard_error:.2g} (profile "
                      f"{estimate.design:.4g}): {mark}; {estimate.reason.split(': ', 1)[-1]}", highlight=False)
    if fit.simex:
        console.print(simex_line(fit), highlight=False)
    console.print(f"  fit rms {fit.rms_error_N:.3g} N, {100 * fit.relative_rms_error:.2g} % of the peak friction "
                  f"{fit.peak_friction_N:.4g} N", highlight=False)
    console.print(f"overlay: {result.overlay_path}; record: {result.record_path}; plot: {result.plot_path}", highlight=False)
    if not fit.determined:
        raise IdentificationError(
            f"the runs {', '.join(str(r.path) for r in result.runs)} determine none of the friction law's parameters"
            + (f": {fit.note}" if fit.note else "") + "; expected a run in which the base mat slides, at high and low "
            "speeds (an earthquake record, or a dry run at a higher PGA)"
        )
    return exit_codes.OK
