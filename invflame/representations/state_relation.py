r"""Flame states from a mixture fraction and a temperature factor: a state relation of the fuel.

Emission grows as :math:`X\,B(T)`: where the gas holds no CO₂ or H₂O the cameras see nothing of
its temperature, and four free fields per voxel (T, X_CO2, X_H2O, X_CH4) let a fit trade
temperature against composition and heat transparent air. A state relation removes both
directions: temperature and mole fractions follow from how much fuel the gas holds.

**The lean branch of methane–air.** Fuel (CH₄ at the ambient temperature) mixes with ambient air
(dry air O₂ + 3.76 N₂ carrying the ambient mole fractions of CO₂, H₂O and CH₄ as inert
diluents) and burns completely, CH₄ + 2 O₂ + 7.52 N₂ → CO₂ + 2 H₂O + 7.52 N₂ (Burke & Schumann
1928; Poinsot & Veynante, *Theoretical and Numerical Combustion*, 2005, sec. 3.2.5), the limit
the OpenFOAM pool fire's infinitely fast one-step chemistry also takes. The state is a function
of the progress :math:`s = z / Z_\text{st} \in [0, 1]`, with :math:`z` the mass fraction of
fuel in the fuel + dry-air mixture and :math:`Z_\text{st}` ≈ 0.0552 its stoichiometric value:
:math:`s = 0` is ambient air, :math:`s = 1` the stoichiometric flame sheet. Per unit mass of the
fuel + dry-air stream the products are :math:`Y_\text{CO2} = z\,W_\text{CO2}/W_\text{CH4}`,
:math:`Y_\text{H2O} = 2z\,W_\text{H2O}/W_\text{CH4}`, the rest O₂ and N₂; the diluents of the
air add their share. The rich side is not represented (its emission is matched by a lean state).

**The temperature factor** :math:`h` scales the temperature rise of the branch,

.. math:: T = T_0 + h\, \Delta T_\text{st}\, s\, b(s),

with :math:`b(s)` the mass share of the fuel + dry-air stream in the gas (the diluents heat
too) and :math:`\Delta T_\text{st}` the rise at stoichiometry for :math:`h = 1`. A time-averaged
or radiating flame holds more or fewer products per kelvin than the adiabatic sheet: the
OpenFOAM pool fire's median :math:`(T - T_0)/(X_\text{CO2} + X_\text{H2O})` is 7800 K, the
branch's at :math:`\Delta T_\text{st}` = 1500 K about 5100 K (``docs/honest.md``). Where
:math:`s = 0` the temperature is ambient whatever :math:`h`: no temperature without products.

Every function here is plain arithmetic on its arguments, so it serves NumPy, JAX and torch
arrays alike (one code for the voxel map, its derivatives and the neural field's output).
"""

from __future__ import annotations

import numpy as np

from invflame.phantoms.composition import AIR_O2_MOLE_FRACTION, MOLAR_MASS, Z_STOICHIOMETRIC

DILUENTS = ("CO2", "H2O", "CH4")
"""The ambient diluents, in field order after T."""

DEFAULT_TEMPERATURE_RISE_ST = 1500.0
"""Temperature rise (K) at the stoichiometric mixture fraction for :math:`h = 1`.

Between the time-averaged rise of a buoyant fire's continuous flame, about 870 K for the 13 kW
pool fire (McCaffrey 1979, :func:`invflame.phantoms.plume.mccaffrey_centreline_rise`; a lower
bound for the flame sheet, which time-averaging mixes with air), and the adiabatic rise of
methane–air, about 1950 K (:func:`~invflame.phantoms.composition.burke_schumann_methane`; an
upper bound, a pool fire loses heat by radiation). On the synthetic plume at peak SNR 1000 the
band-tomography start's MSE_T stays within 0.0010–0.0012 for rises from 1200 to 1800 K."""

DEFAULT_FACTOR_RANGE = (0.3, 2.0)
"""Bounds of the temperature factor :math:`h` (dimensionless). The packaged OpenFOAM pool fire
holds :math:`h` = 1.27–1.75 (5th–95th percentile over its gas with over 1 % of CO₂ + H₂O,
against the default rise of 1500 K: :meth:`StateRelation.invert` of its 60³ field; median
1.52 on the 30³ grid, ``python studies/fit_diagnosis.py``); 0.3 lets a strongly radiating or
diluted gas reach a third of the rise."""


class StateRelation:
    r"""Temperature and mole fractions of methane–air gas from :math:`(s, h)`.

    Parameters
    ----------
    ambient : array_like, shape (4,)
        Ambient air: T in K, then mole fractions of CO2, H2O, CH4 (summing below 1).
    temperature_rise_st : float, optional
        :math:`\Delta T_\text{st}` in K (default :data:`DEFAULT_TEMPERATURE_RISE_ST`).
    factor_range : tuple of float, optional
        Bounds of :math:`h` (default :data:`DEFAULT_FACTOR_RANGE`), ``0 < low <= high``; equal
        bounds hold :math:`h` fixed.
    temperature_max : float, optional
        Highest temperature in K the states may reach (default 2500 K, the absorption table's
        top): the progress is bounded by :attr:`progress_max`, the largest :math:`s \le 1`
        whose state at the highest factor stays below it.

    Attributes
    ----------
    progress_max : float
        Upper bound of :math:`s` (dimensionless).

    Raises
    ------
    ValueError
        For an ambient state that is not a gas, a rise that is not positive or factor bounds
        that do not bracket 1.
    """

    def __init__(self, ambient, temperature_rise_st: float = DEFAULT_TEMPERATURE_RISE_ST,
                 factor_range=DEFAULT_FACTOR_RANGE, temperature_max: float = 2500.0):
        ambient = np.asarray(ambient, dtype=np.float64)
        if ambient.shape != (4,) or ambient[0] <= 0 or np.any(ambient[1:] < 0) \
                or ambient[1:].sum() >= 1:
            raise ValueError("ambient must be (T [K] > 0, X_CO2, X_H2O, X_CH4) with mole "
                             f"fractions >= 0 summing below 1, got {ambient.tolist()}")
        if not temperature_rise_st > 0:
            raise ValueError(f"temperature_rise_st must be positive (K), got "
                             f"{temperature_rise_st}")
        low, high = (float(v) for v in factor_range)
        if not 0 < low <= high:
            raise ValueError(f"factor_range must satisfy 0 < low <= high, got "
                             f"{factor_range}")
        self.ambient = ambient
        self._t0 = float(ambient[0])  # Python floats keep float32 arrays float32
        self.temperature_rise_st = float(temperature_rise_st)
        self.factor_range = (low, high)
        w = MOLAR_MASS
        dry = 1.0 - ambient[1:].sum()
        air_moles = {"O2": AIR_O2_MOLE_FRACTION * dry, "N2": (1 - AIR_O2_MOLE_FRACTION) * dry,
                     **dict(zip(DILUENTS, ambient[1:], strict=True))}
        air_mass = {s: x * w[s] for s, x in air_moles.items()}
        total = sum(air_mass.values())
        self._dry_share = float((air_mass["O2"] + air_mass["N2"]) / total)
        self._diluent = {s: float(air_mass[s] / total) for s in DILUENTS}  # mass fraction in air
        self._y_o2 = float(air_mass["O2"] / (air_mass["O2"] + air_mass["N2"]))  # in dry air
        if not temperature_max > ambient[0]:
            raise ValueError(f"temperature_max must lie above the ambient {ambient[0]:g} K, got "
                             f"{temperature_max}")
        progress = np.linspace(0.0, 1.0, 10001)
        hottest = self.states(progress, high)[0]  # increasing in s
        self.progress_max = float(progress[hottest <= temperature_max][-1])

    def mixture_fraction(self, s):
        """Mass fraction of the gas that came from the fuel stream, for progress ``s``."""
        z = s * Z_STOICHIOMETRIC
        return z * self._dry_share / (1.0 - z * (1.0 - self._dry_share))

    def states(self, s, h=1.0):
        r"""T in K and mole fractions of CO2, H2O, CH4 at progress ``s`` and factor ``h``.

        Parameters
        ----------
        s : array_like
            :math:`z / Z_\text{st}` in [0, 1] (values outside extrapolate the formulas; the
            representations keep them inside by bounds).
        h : array_like, optional
            Temperature factor, broadcastable with ``s`` (default 1).

        Returns
        -------
        tuple of 4 arrays
            ``(T, X_CO2, X_H2O, X_CH4)``, each of the broadcast shape, in the array type of
            the arguments.
        """
        w = MOLAR_MASS
        z = s * Z_STOICHIOMETRIC
        mixture = self.mixture_fraction(s)
        burnt = mixture + (1.0 - mixture) * self._dry_share  # share of fuel + dry air
        air = 1.0 - mixture
        moles = {
            "CO2": (burnt * z / w["CH4"] + air * self._diluent["CO2"] / w["CO2"]),
            "H2O": (burnt * 2.0 * z / w["CH4"] + air * self._diluent["H2O"] / w["H2O"]),
            "CH4": air * self._diluent["CH4"] / w["CH4"],
            "O2": burnt * (self._y_o2 * (1.0 - z) - 2.0 * z * w["O2"] / w["CH4"]) / w["O2"],
            "N2": burnt * (1.0 - self._y_o2) * (1.0 - z) / w["N2"],
        }
        total = moles["CO2"] + moles["H2O"] + moles["CH4"] + moles["O2"] + moles["N2"]
        temperature = self._t0 + h * self.temperature_rise_st * s * burnt
        return (temperature, *(moles[sp] / total for sp in DILUENTS))

    def invert(self, fields, n_points: int = 4097) -> tuple[np.ndarray, np.ndarray]:
        r"""The :math:`(s, h)` closest to physical fields, within the bounds.

        :math:`s` matches the fields' CO₂ + H₂O above ambient (monotone in :math:`s`),
        :math:`h` their temperature rise at that :math:`s` (1 where :math:`s` is below 1e-3:
        nothing there tells :math:`h`); both clipped to their bounds (:math:`s` to
        [0, :attr:`progress_max`]). Exact for states of the relation inside the bounds.

        Parameters
        ----------
        fields : array_like, shape (4, ...)
            T in K and mole fractions of CO2, H2O, CH4.
        n_points : int, optional
            Resolution of the table inverted for :math:`s`.

        Returns
        -------
        s, h : ndarray
            Each of shape ``fields.shape[1:]``, float64.
        """
        fields = np.asarray(fields, dtype=np.float64)
        if fields.ndim < 1 or fields.shape[0] != 4:
            raise ValueError(f"fields must have shape (4, ...) (T, CO2, H2O, CH4), got "
                             f"{fields.shape}")
        grid = np.linspace(0.0, 1.0, int(n_points))
        _, co2, h2o, _ = self.states(grid)
        s = np.interp(fields[1] + fields[2], co2 + h2o, grid)
        rise = self.temperature_rise_st * s * (self.mixture_fraction(s) + (
            1.0 - self.mixture_fraction(s)) * self._dry_share)
        seen = s > 1e-3
        h = np.where(seen, (fields[0] - self.ambient[0]) / np.where(seen, rise, 1.0), 1.0)
        return np.minimum(s, self.progress_max), np.clip(h, *self.factor_range)
