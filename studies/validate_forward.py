r"""Validate invflame's forward model against an independent line-by-line reference (HAPI).

Usage::

    python studies/validate_forward.py [--cases slab|layers|between|all] [--quick] [--split]
        [--broadening local|fixed] [--points-per-bin N]

What it measures: the spectral radiance (W/(m²·sr·cm⁻¹)) leaving homogeneous gas layers at
1 atm in front of a cold background, on invflame's 0.04 cm⁻¹ line-by-line bins over
650–725 cm⁻¹, from invflame's default forward path (:func:`invflame_radiance`: the default
absorption table, the emission kernel in float32) and from the HAPI reference of
``studies/hapi_reference.py`` (HAPI Voigt cross-sections on a 0.0025 cm⁻¹ grid, each gas
self-broadened at its own mole fraction, the radiance averaged over each bin). Cases:

* ``slab``: one 0.2 m layer for every T in {800, 1500, 2000} K, X_H2O in {0.02, 0.12, 0.25},
  X_CO2 in {0.03, 0.10} (18 cases);
* ``layers``: two 0.1 m layers at 800 K and 1800 K (X_CO2 = 0.10, X_H2O = 0.12), the cool one
  nearer the camera and then the hot one;
* ``between``: 0.5 m slabs at 1200 K and 2300 K, X_CO2 = 0.06 and X_H2O in {0.01, 0.035,
  0.08, 0.14, 0.35}: states between the absorption table's nodes of temperature and H2O
  fraction and between the compositions above (10 cases);
* ``--quick``: four cases (two slabs, the cool-in-front pair of layers, one ``between``).

Per case it prints, as invflame / reference − 1: the band integral over 650–725 cm⁻¹; over
1 cm⁻¹ bins (25 consecutive 0.04 cm⁻¹ bins from 650.00 cm⁻¹) the median and maximum absolute
difference and where the maximum lies; and after the instrument lineshape (triangular
apodization, 8 cm⁻¹ resolution, :class:`operators.ils.ILSConvolution`) applied to both spectra
the median and maximum absolute difference. A last line gives the worst case of each against
the acceptance: band within 0.3 %, every 1 cm⁻¹ bin within 1 %, after the lineshape within
0.5 %.

``--split`` adds four columns that split the band and worst 1 cm⁻¹ differences in two: invflame
against the reference solved on bin-averaged optical depths (``hapi_reference.radiance(layers,
"optical depth")``: cross-sections, their tables and the kernel), and that reference against
the exact one (the mean of the optical depth over a bin in place of the mean of the
transmission).

Run time on 2 CPU cores: the HAPI reference computes 29 cross-sections on its first run (about
12 s per CO2 state, 1 s per H2O state), then reads them from its cache
(``$INVFLAME_CACHE/hapi``, default ``~/.cache/invflame/hapi``); invflame builds its absorption
table once (about a minute for the default one), then reads it from its cache. Measured: the
first 20 cases took 95 s with an empty HAPI cache and 3 s with both caches warm; the ten
``between`` cases 84 s with their HAPI cross-sections and invflame's table to compute.
"""

from __future__ import annotations

import argparse
import functools
import sys
import time

import hapi_reference
import numpy as np

from invflame.spectroscopy.absorption_table import AbsorptionTable
from invflame.spectroscopy.table_inputs import BROADENING
from operators.ils import ILSConvolution
from operators.rte.kernel import emission_radiance
from operators.rte.tables import RTETables

#: Acceptance, relative: band integral, every 1 cm⁻¹ bin, every point after the lineshape.
ACCEPT_BAND = 0.003
ACCEPT_WIDE = 0.01
ACCEPT_ILS = 0.005
#: Consecutive 0.04 cm⁻¹ bins in one 1 cm⁻¹ bin.
WIDE = 25
RESOLUTION = 8.0  # cm⁻¹


# -- invflame's side ---------------------------------------------------------------------------
@functools.cache
def _invflame_tables(broadening: str, points_per_bin: int) -> RTETables:
    return AbsorptionTable.default(progress=False, self_fraction=BROADENING[broadening],
                                   subdivision=points_per_bin).kernel_tables()


def invflame_radiance(layers, broadening: str = "local", points_per_bin: int = 8
                      ) -> np.ndarray:
    """Spectral radiance of homogeneous layers from invflame's default forward path.

    The default absorption table (:meth:`AbsorptionTable.default`), its kernel tables in
    float32 (:meth:`AbsorptionTable.kernel_tables` defaults, as a reconstruction's) and the
    emission kernel (:func:`emission_radiance`) for one ray whose segments are the layers; no
    CH4, cold background.

    Parameters
    ----------
    layers : sequence of (float, float, float, float)
        ``(T, X_CO2, X_H2O, length)`` per layer, nearest the camera first: K, mole fractions
        (dimensionless), m.
    broadening : {"local", "fixed"}, optional
        Self broadening from each layer's own fractions (default) or at fixed fractions
        (``spectrum.broadening``).
    points_per_bin : int, optional
        Most spectral points per bin (``spectrum.points_per_bin``, default 8).

    Returns
    -------
    ndarray, shape (1876,)
        Radiance in W/(m²·sr·cm⁻¹) on the 0.04 cm⁻¹ bins of 650–725 cm⁻¹.
    """
    tables = _invflame_tables(broadening, points_per_bin)
    layers = np.asarray(layers, dtype=np.float64).reshape(-1, 4)
    fields = np.zeros((4, 1, len(layers)))  # T, X_CO2, X_H2O, X_CH4
    fields[:3, 0] = layers[:, :3].T
    lengths = layers[None, :, 3]
    return np.asarray(emission_radiance(tables, fields, lengths)[0], dtype=np.float64)


# -- cases and measures ------------------------------------------------------------------------
def cases(which: str, quick: bool) -> list[tuple[str, list]]:
    """The cases as ``(label, layers)``, layers as for :func:`invflame_radiance`."""
    slabs = [
        (f"slab {t:g} K, X_H2O {h:g}, X_CO2 {c:g}", [(t, c, h, 0.2)])
        for t in (800.0, 1500.0, 2000.0) for h in (0.02, 0.12, 0.25) for c in (0.03, 0.10)
    ]
    cool, hot = (800.0, 0.10, 0.12, 0.1), (1800.0, 0.10, 0.12, 0.1)
    layers = [("800 K in front of 1800 K", [cool, hot]),
              ("1800 K in front of 800 K", [hot, cool])]
    between = [
        (f"slab {t:g} K, X_H2O {h:g}, X_CO2 0.06, {length:g} m", [(t, 0.06, h, length)])
        for t in (1200.0, 2300.0) for h in (0.01, 0.035, 0.08, 0.14, 0.35) for length in (0.5,)
    ]
    if quick:
        slabs = [s for s in slabs if s[0] in ("slab 1500 K, X_H2O 0.12, X_CO2 0.1",
                                              "slab 800 K, X_H2O 0.02, X_CO2 0.03")]
        layers, between = layers[:1], between[:1]
    return {"slab": slabs, "layers": layers, "between": between,
            "all": slabs + layers + between}[which]


def compare(model, reference, wavenumber, ils: ILSConvolution) -> dict:
    """Relative differences (model / reference − 1) of two spectra on the 0.04 cm⁻¹ bins.

    Parameters
    ----------
    model, reference : ndarray, shape (n_eta,)
        Radiance in W/(m²·sr·cm⁻¹).
    wavenumber : ndarray, shape (n_eta,)
        Bin centres in cm⁻¹.
    ils : ILSConvolution
        The instrument lineshape on ``wavenumber`` for one spectrum.

    Returns
    -------
    dict
        ``band`` (signed), ``wide_median``, ``wide_max`` (absolute, over 1 cm⁻¹ bins),
        ``wide_at`` (cm⁻¹, centre of the worst 1 cm⁻¹ bin), ``ils_median``, ``ils_max``
        (absolute), ``ils_at`` (cm⁻¹).
    """
    n_wide = wavenumber.size // WIDE

    def wide(values):
        return values[: n_wide * WIDE].reshape(n_wide, WIDE).mean(axis=1)

    centres = wide(wavenumber)
    relative = np.abs(wide(model) / wide(reference) - 1.0)
    convolved = [ils(x[None, :])[0] for x in (model, reference)]
    after = np.abs(convolved[0] / convolved[1] - 1.0)
    return {
        "band": model.sum() / reference.sum() - 1.0,
        "wide_median": np.median(relative), "wide_max": relative.max(),
        "wide_at": centres[relative.argmax()],
        "ils_median": np.median(after), "ils_max": after.max(),
        "ils_at": ils.out_wavenumber[after.argmax()],
    }


def _row(label: str, m: dict, parts: tuple = ()) -> str:
    row = (f"| {label} | {100 * m['band']:+.3f} | {100 * m['wide_median']:.3f} | "
           f"{100 * m['wide_max']:.3f} | {m['wide_at']:.2f} | {100 * m['ils_median']:.3f} | "
           f"{100 * m['ils_max']:.3f} | {m['ils_at']:.1f} |")
    return row + "".join(f" {100 * p['band']:+.3f} | {100 * p['wide_max']:.3f} |" for p in parts)


def _verdict(value: float, limit: float) -> str:
    return f"{100 * value:.3f} % ({'pass' if value <= limit else 'FAIL'}, ≤ {100 * limit:g} %)"


def main(argv=None) -> int:
    """Print the comparison table and the worst case against the acceptance."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", choices=("slab", "layers", "between", "all"), default="all",
                        help="which cases (default all)")
    parser.add_argument("--quick", action="store_true", help="three cases only")
    parser.add_argument("--broadening", choices=sorted(BROADENING), default="local",
                        help="invflame's self broadening (default local)")
    parser.add_argument("--points-per-bin", type=int, default=8,
                        help="invflame's most spectral points per bin (default 8; 1: one "
                        "optical depth per bin)")
    parser.add_argument("--split", action="store_true",
                        help="split the differences: tables and kernel, in-bin transmission")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    wavenumber = hapi_reference.bin_centres()
    ils = ILSConvolution(wavenumber, 1, resolution=RESOLUTION)
    chosen = cases(args.cases, args.quick)
    print(f"invflame / HAPI reference - 1, in %; {len(chosen)} cases, 1 atm, cold background; "
          f"1 cm-1 bins of {WIDE} x 0.04 cm-1 from 650.00 cm-1; ILS {RESOLUTION:g} cm-1; "
          f"invflame's broadening {args.broadening}, up to {args.points_per_bin} points per bin")
    print()
    split = (" kernel band | kernel 1 cm⁻¹ max | in-bin τ band | in-bin τ 1 cm⁻¹ max |"
             if args.split else "")
    print("| case | band | 1 cm⁻¹ median | 1 cm⁻¹ max | at [cm⁻¹] | ILS median | ILS max | "
          "at [cm⁻¹] |" + split)
    print("|---|---:|---:|---:|---:|---:|---:|---:|" + "---:|" * (4 * args.split))
    results, spent = [], {"reference": 0.0, "invflame": 0.0}
    for label, layers in chosen:
        tic = time.perf_counter()
        reference = hapi_reference.radiance(layers)
        spent["reference"] += time.perf_counter() - tic
        tic = time.perf_counter()
        model = invflame_radiance(layers, args.broadening, args.points_per_bin)
        spent["invflame"] += time.perf_counter() - tic
        results.append(compare(model, reference, wavenumber, ils))
        parts = ()
        if args.split:
            averaged = hapi_reference.radiance(layers, "optical depth")
            parts = (compare(model, averaged, wavenumber, ils),
                     compare(averaged, reference, wavenumber, ils))
        print(_row(label, results[-1], parts), flush=True)
    band = max(abs(m["band"]) for m in results)
    wide = max(m["wide_max"] for m in results)
    after = max(m["ils_max"] for m in results)
    print()
    print(f"worst of {len(results)} cases: band {_verdict(band, ACCEPT_BAND)}; 1 cm-1 bin "
          f"{_verdict(wide, ACCEPT_WIDE)}; after the ILS {_verdict(after, ACCEPT_ILS)}")
    print(f"time: reference {spent['reference']:.1f} s, invflame {spent['invflame']:.1f} s, "
          f"total {time.perf_counter() - started:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
