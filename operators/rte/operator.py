r"""Emission radiative transfer along fixed rays as an :class:`~operators.base.Operator`.

The model and its derivatives are those of the emission kernel (:mod:`operators.rte.kernel`,
tables prepared by :mod:`operators.rte.tables`, rays batched by :mod:`operators.rte.batches`).
:class:`KernelOperator` turns any JAX map built around the kernel — the kernel alone
(:class:`EmissionRTE`), or a whole measurement with sampling before it and instrument after
it — into an operator whose value, ``jvp``, ``vjp`` and ``linearize`` all come from that one
map (a :class:`~operators.jax_operator.JaxFunction`): the value and the reverse mode through
the kernel's custom VJP, the forward mode through JAX's JVP of the same map built on the
forward-mode kernel.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np

from operators.base import Jacobian, JaxMap, Operator, precision
from operators.interop import to_jax
from operators.jax_operator import JaxFunction
from operators.rte.batches import batch_rays_for
from operators.rte.kernel import check_background, emission_radiance, radiance_kernel
from operators.rte.tables import RTETables

__all__ = ["EmissionRTE", "KernelOperator"]


class KernelOperator(Operator):
    r"""An operator :math:`x \mapsto m(a, x)` from a JAX map built around the emission kernel.

    ``build(radiance)`` returns the map ``m(*args, x)``, given the kernel as
    ``radiance(tables, fields, lengths)`` (:func:`operators.rte.kernel.radiance_kernel`). It
    is built twice from the same code: on the reverse-mode kernel for the value, ``vjp`` and
    ``linearize`` (:attr:`function`), on the forward-mode kernel for ``jvp``; the two give the
    same values, so ``jvp`` and ``vjp`` are the exact derivatives of :attr:`function`.

    Parameters
    ----------
    build : callable
        ``build(radiance) -> m``, ``m(*args, x) -> y`` a JAX-traceable map from ``x`` of shape
        ``dims`` to ``y`` of shape ``dimsd``.
    args : tuple
        Constant arguments of ``m`` (pytrees of arrays: tables, ray geometry); passed at every
        call, so that they are not compiled in as constants.
    batch_rays : int
        Rays per batch of the kernel.
    dims, dimsd : tuple of int
        Input and output shapes.
    dtype : numpy dtype
        Of inputs and outputs.
    name : str
        Label for messages.
    domain : callable, optional
        ``domain(x)`` raises ``ValueError`` (saying what is wrong) for a point ``x`` outside the
        map's domain, where it would return garbage (e.g. temperatures outside the absorption
        tables); called at every point the operator is evaluated or linearized at, not on the
        directions ``v``, ``w``. Default None: no check.

    Attributes
    ----------
    function : callable
        ``function(*args, x) -> y``, the jitted map, differentiable in reverse mode
        (:func:`jax.vjp`, :func:`jax.grad`).
    args : tuple
    """

    def __init__(self, build: Callable, args: tuple, batch_rays: int, dims, dimsd, dtype,
                 name: str, domain: Callable | None = None):
        super().__init__(dims, dimsd, dtype=dtype, name=name)
        self.domain = domain
        self.batch_rays = int(batch_rays)
        self._map = JaxFunction(
            build(radiance_kernel(self.batch_rays)), self.dtype, args,
            forward_mode=build(radiance_kernel(self.batch_rays, forward_mode=True)))
        self.function, self.args = self._map.function, self._map.args

    def jax_map(self) -> JaxMap:
        """:attr:`function` on :attr:`args`, checked by :attr:`domain`."""
        return JaxMap(lambda args, x: self.function(*args, x), self.args, self.domain)

    def _at(self, x):
        """The point ``x``, once :attr:`domain` has taken it."""
        if self.domain is not None:
            self.domain(x)
        return x

    def _forward(self, x):
        return self._map.forward(self._at(x))

    def _jvp(self, x, v):
        return self._map.jvp(self._at(x), v)

    def _vjp(self, x, w):
        return self._map.vjp(self._at(x), w)

    def linearize(self, x) -> Jacobian:
        """One forward pass, keeping the kernel's pullback for the vjp."""
        x = self._at(self._as_input(x))
        value, jvp, vjp = self._map.pullback(x)
        return Jacobian(self, x, self._result(value, self.dimsd, "forward"), jvp=jvp, vjp=vjp)


def _radiance_of_fields(radiance):
    """The kernel as a map ``(tables, lengths, background, fields) -> radiance`` (the
    operator's input last)."""
    return lambda tables, lengths, background, fields: radiance(tables, fields, lengths,
                                                                background)


class EmissionRTE(KernelOperator):
    r"""Emission radiative transfer along fixed rays, a nonlinear operator.

    Maps per-segment fields ``(tables.n_fields, n_rays, n_seg)`` — temperature (K) and mole
    fractions (dimensionless), field order (T, CO2, H2O, CH4), then the soot volume fraction
    when built with ``soot`` — to spectral radiance
    ``(n_rays, n_eta)`` in W/(m²·sr·cm⁻¹), optionally in front of a fixed background
    radiance seen through each ray's transmittance; see :mod:`operators.rte.kernel` for the
    model.
    ``jvp`` and ``vjp`` are the exact derivatives of the discrete forward map. Build it from
    cross-section splines, or with :meth:`from_tables` from tables prepared already.

    Parameters
    ----------
    wavenumber : array_like, shape (n_eta,)
        Wavenumbers in cm⁻¹.
    temperatures : array_like, shape (n_T,)
        Temperature nodes in K of the cross-section splines.
    coef : array_like, shape (4, n_T - 1, n_columns, n_eta)
        :class:`~operators.tabulated.PiecewiseCubic` coefficients of the cross-sections in
        cm²/molecule, one column per species (or per species and fraction node).
    lengths : array_like, shape (n_rays, n_seg)
        Segment lengths in m, nearest the camera first; zero on padding.
    pressure : float, optional
        Total pressure in Pa (default 101325).
    dtype : numpy dtype, optional
        float32 (default) or float64.
    planck : {"table", "exact"}, optional
        See :meth:`RTETables.from_spline`.
    memory_budget : int, optional
        Bytes for one batch of rays (default :data:`DEFAULT_MEMORY_BUDGET`, per backend);
        ignored when ``batch_rays`` is given.
    batch_rays : int, optional
        Rays per batch.
    soot : float, optional
        The Rayleigh soot constant :math:`C` (:func:`operators.rte.tables.rayleigh_soot_constant`):
        the input gains a soot volume fraction field, absorbing :math:`C f_v \eta \cdot 10^2`
        m⁻¹. Default None: no soot.
    background : array_like, shape (n_rays, n_eta) or (n_eta,), optional
        Radiance behind the far end of each ray in W/(m²·sr·cm⁻¹) (default None: none).
    fraction_nodes : sequence of sequence of float, optional
        Per species, the mole fractions of its columns of ``coef``: cross-sections that
        depend on the species' own mole fraction (:meth:`RTETables.from_spline`). Default: one
        column per species.

    Attributes
    ----------
    tables : RTETables
    lengths : jax.Array, shape (n_rays, n_seg)
    background : jax.Array, shape (n_rays, n_eta), or None
    batch_rays : int
    kernel : callable
        ``kernel(fields, lengths) -> radiance``: :func:`emission_radiance` on these tables
        and this background, a differentiable JAX function taking new segment lengths (m) at
        every call. Inside
        another jitted function prefer :func:`emission_radiance` with the tables as an
        argument, so they are not compiled in as constants.
    """

    def __init__(self, wavenumber, temperatures, coef, lengths, pressure: float = 101325.0,
                 dtype=np.float32, planck: str = "table", memory_budget: int | None = None,
                 batch_rays: int | None = None, background=None, soot: float | None = None,
                 fraction_nodes=None):
        tables = RTETables.from_spline(wavenumber, temperatures, coef, pressure, dtype, planck,
                                       soot=soot, fraction_nodes=fraction_nodes)
        self._setup(tables, lengths, memory_budget, batch_rays, background)

    @classmethod
    def from_tables(cls, tables: RTETables, lengths, memory_budget: int | None = None,
                    batch_rays: int | None = None, background=None) -> EmissionRTE:
        """The operator on prepared tables (their dtype is the operator's).

        Parameters
        ----------
        tables : RTETables
            From :meth:`RTETables.from_spline`.
        lengths, memory_budget, batch_rays, background
            As for :class:`EmissionRTE`.
        """
        if not isinstance(tables, RTETables):
            raise TypeError(f"tables must be an operators.rte.tables.RTETables (build one with "
                            f"RTETables.from_spline), got {type(tables).__name__}")
        operator = cls.__new__(cls)
        operator._setup(tables, lengths, memory_budget, batch_rays, background)
        return operator

    def _setup(self, tables: RTETables, lengths, memory_budget, batch_rays, background) -> None:
        lengths = np.asarray(lengths)
        if lengths.ndim != 2:
            raise ValueError(f"lengths must have shape (n_rays, n_seg) in m, got {lengths.shape}")
        n_rays, n_seg = lengths.shape
        batch_rays = int(batch_rays or batch_rays_for(tables, n_rays, memory_budget))
        dtype = np.dtype(tables.dtype)
        self.tables = tables
        with precision(dtype):
            self.lengths = to_jax(lengths, dtype=dtype)
            self.background = check_background(tables, background, n_rays)
        super().__init__(_radiance_of_fields, (tables, self.lengths, self.background), batch_rays,
                         (tables.n_fields, n_rays, n_seg), (n_rays, tables.n_eta), dtype,
                         "EmissionRTE", domain=self._check_segments)
        self._traversed = lengths > 0
        self.kernel = partial(emission_radiance, tables, batch_rays=batch_rays,
                              background=self.background)

    def _check_segments(self, fields) -> None:
        """Refuse segment fields the tables cannot evaluate: on the segments of non-zero
        length, non-finite values, temperatures outside the tables' nodes (K, up to the
        fields' rounding) and negative mole or volume fractions (padding is not looked at)."""
        fields = np.asarray(fields)[:, self._traversed]
        names = ["T", *(f"mole fraction (field {i + 1})" for i in range(self.tables.n_species)),
                 *(["soot volume fraction"] if self.tables.soot else [])]
        for name, values in zip(names, fields, strict=True):
            if not np.isfinite(values).all():
                raise ValueError(f"{self.name}: the {name} field holds NaN or inf")
        self.tables.check_temperature(fields[0], self.name)
        for name, values in zip(names[1:], fields[1:], strict=True):
            if values.min() < 0:
                raise ValueError(f"{self.name}: the {name} field is negative (minimum "
                                 f"{values.min():g}); fractions must be >= 0")
