"""``invflame lines``: look at the absorption cross-sections and a slab emission spectrum."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from invflame.cli import arguments
from invflame.errors import ConfigError

if TYPE_CHECKING:
    import numpy as np


def add_parser(subparsers) -> None:
    """Register ``lines plot``."""
    parser = subparsers.add_parser(
        "lines",
        help="absorption cross-sections of CO2 and H2O (650-725 cm-1) and slab emission",
        description="Figures of the default absorption table (built on first use, then cached).",
    )
    sub = parser.add_subparsers(dest="lines_command", required=True)
    plot = sub.add_parser(
        "plot",
        help="PNG of sigma(eta) for CO2 and H2O, and an instrument-convolved slab spectrum",
        description="Top: cross-sections of CO2 and H2O (cm2/molecule, log scale) at the given "
        "temperatures. Bottom: radiance of a homogeneous slab, I = B(T)(1 - exp(-kappa L)), "
        "line by line and convolved with the FTIR lineshape (triangular apodization, sinc^2).",
    )
    plot.add_argument("--out", type=arguments.png, required=True,
                      help="output PNG file (.png is added to a name without a suffix)")
    plot.add_argument(
        "--temperatures", type=arguments.positive, nargs="+", default=[300.0, 1000.0, 1500.0],
        help="temperatures of the cross-section curves, K (default 300 1000 1500)",
    )
    plot.add_argument(
        "--slab-temperature", type=arguments.positive, default=1300.0,
        help="slab temperature, K (default 1300)",
    )
    plot.add_argument(
        "--length", type=arguments.positive, default=0.1, help="slab thickness, m (default 0.1)"
    )
    plot.add_argument(
        "--x-co2", type=arguments.fraction, default=0.1,
        help="CO2 mole fraction of the slab and of the gas of the cross-sections (default 0.1)",
    )
    plot.add_argument(
        "--x-h2o", type=arguments.fraction, default=0.2,
        help="H2O mole fraction of the slab and of the gas of the cross-sections (default 0.2)",
    )
    plot.add_argument(
        "--resolution", type=arguments.positive, default=8.0,
        help="instrument resolution 1/MOPD, cm-1 (default 8)",
    )
    plot.set_defaults(func=run)


def slab_radiance(table, temperature: float, mole_fractions, length: float) -> np.ndarray:
    """Radiance of a homogeneous slab seen through its thickness, W/(m²·sr·cm⁻¹).

    Parameters
    ----------
    table : AbsorptionTable
    temperature : float
        K.
    mole_fractions : array_like, shape (n_species,)
        In the order of ``table.species``.
    length : float
        Slab thickness in m.
    """
    import numpy as np

    from operators.rte.planck import planck

    kappa = table.kappa(np.asarray(temperature), np.asarray(mole_fractions, dtype=float))
    return planck(table.wavenumber, temperature) * -np.expm1(-kappa * length)


def run(args: argparse.Namespace) -> int:
    """Draw the figure; returns 0."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from invflame.spectroscopy.absorption_table import AbsorptionTable
    from operators.ils import ILSConvolution
    from operators.rte.planck import planck

    if args.x_co2 + args.x_h2o > 1.0:
        raise ConfigError(f"--x-co2 {args.x_co2:g} plus --x-h2o {args.x_h2o:g} exceed 1: mole "
                          "fractions of one gas sum to at most 1")
    table = AbsorptionTable.default()
    lo, hi = table.temperatures[[0, -1]]
    for name, value in [("--temperatures", t) for t in args.temperatures] + [
            ("--slab-temperature", args.slab_temperature)]:
        if not lo <= value <= hi:
            raise ConfigError(f"{name} {value:g} K lies outside the absorption table's "
                              f"{lo:g}-{hi:g} K")
    eta = table.wavenumber
    fractions = np.zeros(len(table.species))
    fractions[table.species.index("CO2")] = args.x_co2
    fractions[table.species.index("H2O")] = args.x_h2o
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 8), sharex=True)
    colors = plt.get_cmap("plasma")(np.linspace(0.0, 0.8, len(args.temperatures)))
    for temperature, color in zip(args.temperatures, colors, strict=True):
        sigma = table.cross_sections(np.asarray(temperature), fractions)
        for name, style in (("CO2", "-"), ("H2O", ":")):
            top.semilogy(
                eta, sigma[table.species.index(name)], style, color=color, lw=0.6,
                label=f"{name} {temperature:g} K",
            )
    top.set_ylabel("σ [cm²/molecule]")
    top.set_ylim(bottom=1e-24)
    top.legend(ncol=len(args.temperatures), fontsize=8)
    top.set_title("Absorption cross-sections at 1 atm (bin averages over 0.04 cm⁻¹), in a gas "
                  f"of {100 * args.x_co2:g} % CO2 and {100 * args.x_h2o:g} % H2O")

    radiance = slab_radiance(table, args.slab_temperature, fractions, args.length)
    ils = ILSConvolution(eta, n_rays=1, resolution=args.resolution)
    measured = ils.matvec(radiance[None, :].ravel()).reshape(ils.dimsd)[0]
    bottom.plot(eta, radiance, color="0.7", lw=0.5, label="line by line")
    bottom.plot(
        ils.out_wavenumber, measured, "o-", color="C3", ms=3,
        label=f"instrument, {args.resolution:g} cm⁻¹ (triangular apodization)",
    )
    bottom.plot(eta, planck(eta, args.slab_temperature), "k--", lw=0.8, label="blackbody")
    bottom.set_xlabel("wavenumber η [cm⁻¹]")
    bottom.set_ylabel("I [W/(m²·sr·cm⁻¹)]")
    bottom.set_title(
        f"Slab {100 * args.length:g} cm, {args.slab_temperature:g} K, "
        f"{100 * args.x_co2:g} % CO2, {100 * args.x_h2o:g} % H2O"
    )
    bottom.legend(fontsize=8)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=120)
    plt.close(fig)
    print(f"wrote {args.out}")
    return 0
