r"""The emission kernel's sweeps compiled for CPUs by Numba: forward, forward-mode, reverse.

The sweeps of :mod:`operators.rte.kernel` (module notes there: the derivatives, the segment
weights, the table rows) need, per segment of a ray, the optical depth and Planck spectra
from gathered table rows and the running products :math:`P_k`; the forward-mode sweep also
the tangents of the optical depth, the reverse sweep the running sums :math:`I_{\le k}` and
``n_tau + 1`` sums over wavenumber. XLA's CPU backend does not fuse a gathered row into its
several consumers and writes each intermediate spectrum of a ray batch to memory; here one ray
is swept at a time, camera side first, its spectra (a few KiB each) stay in the core's cache,
and each table row is read once per segment. Rays run in parallel over the CPU's cores
(``numba.prange``), longest first. The forward and forward-mode sweeps take two consecutive
segments of a ray that lie in the same temperature interval (most do) in one pass, their table
rows and running spectra read once for both; the reverse sweep, which holds ``n_tau + 1`` sums
per segment, takes one at a time (two were slower with 256-bit vectors; with 512-bit ones they
changed its time by −8 to +1 % in five trials, too little for a second loop).

The sweeps' source (:mod:`operators.rte.numba_source`, its arithmetic in
:mod:`operators.rte.numba_arithmetic`) is written out for the tables' number of gases into a
file of its own (:func:`_source_file`), one per float dtype, which Numba compiles on first use
(2–6 s per sweep in float32 on two cores, first-call times) and caches on disk
(:func:`compiled_sweeps`).

XLA runs each sweep on its own buffers: :func:`target` names a handler of XLA's typed FFI
(:mod:`operators.rte.xla_ffi`) that reads the operands and writes the results in place, where a
host callback (:func:`jax.pure_callback`) would copy both (about 4 ms of a forward evaluation and
12 ms of a gradient's at the paper's size, ``docs/performance.md``).

The XLA sweeps (:mod:`operators.rte.sweeps_xla`) stay those of other backends; both are tested
against one reference formal solution (``tests/operators/test_rte_backends.py``), and
``benchmarks/bench_rte.py`` times both.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import os
import sys
import tempfile
from pathlib import Path
from types import ModuleType

import numba
import numpy as np

from operators.disk_cache import cache_dir
from operators.rte import numba_arithmetic, xla_ffi
from operators.rte.numba_source import TEMPLATE, gas_code
from operators.rte.xla_ffi import HANDLER, ffi_target

__all__ = ["KINDS", "compiled_sweeps", "target"]

#: The modules whose code the compiled sweeps inline besides their own source: the arithmetic
#: and the FFI access to XLA's buffers.
_COMPILED_FROM = (numba_arithmetic, xla_ffi)


@functools.cache
def compiled_sweeps(n_gas: int, n_tau: int, dtype: str) -> ModuleType:
    """The sweeps of :data:`operators.rte.numba_source.TEMPLATE` for ``n_gas`` gases,
    ``n_tau`` rows of the optical depth (``n_tau - n_gas`` soot rows) and float ``dtype``: a
    module of ``forward``, ``forward_mode``, ``reverse`` and their handlers, compiled by Numba
    on first use and cached on disk (:func:`_source_file`)."""
    if not 0 <= n_gas <= n_tau <= n_gas + 1:
        raise ValueError(f"the sweeps take n_gas >= 0 gases and at most one soot row; got "
                         f"n_gas = {n_gas}, n_tau = {n_tau} rows of the optical depth")
    if dtype not in ("float32", "float64"):
        raise ValueError(f"the sweeps run in float32 or float64; got {dtype}")
    path = _source_file(TEMPLATE.format(dtype=dtype, **gas_code(n_gas, n_tau)),
                        f"sweeps_{n_gas}_gases_{n_tau - n_gas}_soot_{dtype}")
    spec = importlib.util.spec_from_file_location(f"{__name__}_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # where Numba's cache finds the sweeps' globals
    spec.loader.exec_module(module)
    return module


def _source_file(source: str, stem: str) -> Path:
    """``source`` as a Python file of its own, where Numba's disk cache can find it.

    The name carries a hash of the source and of :data:`_COMPILED_FROM`, so a file once
    written never changes (Numba keys its cache on the file's time stamp, not on the code the
    sweeps inline from other modules; a change to that code makes new files). A file found
    there is read back and used only if it holds ``source`` exactly; one that does not
    (damaged, cut short) is written again, which also gives it a new time stamp, so that Numba
    compiles it afresh. Each write fills a uniquely named temporary file, flushes it to disk
    and renames it over the file: no process reads half a file. The folder is ``sweeps`` in
    :func:`operators.disk_cache.cache_dir`, or, if that cannot be written, ``invflame-sweeps``
    in the temporary directory.
    """
    compiled_from = b"".join(Path(m.__file__).read_bytes() for m in _COMPILED_FROM)
    digest = hashlib.sha256(source.encode() + compiled_from).hexdigest()[:16]
    folders = (cache_dir() / "sweeps", Path(tempfile.gettempdir()) / "invflame-sweeps")
    for folder in folders:
        path = folder / f"{stem}_{digest}.py"
        try:
            if not _holds(path, source):
                folder.mkdir(parents=True, exist_ok=True)
                fd, partial = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.")
                try:
                    with os.fdopen(fd, "w", encoding="utf-8") as handle:
                        handle.write(source)
                        handle.flush()
                        os.fsync(handle.fileno())
                    os.replace(partial, path)
                except BaseException:
                    os.unlink(partial)
                    raise
            return path
        except OSError as error:
            failure = error
    raise OSError(f"cannot write the compiled sweeps' source to {folders[0]} or "
                  f"{folders[1]}; set INVFLAME_CACHE to a writable folder") from failure


def _holds(path: Path, source: str) -> bool:
    """Whether the file ``path`` exists and holds ``source`` exactly."""
    try:
        return path.read_bytes() == source.encode()
    except FileNotFoundError:
        return False


#: The sweeps, by the names :func:`target` takes.
KINDS = ("forward", "forward_mode", "reverse")


@functools.cache
def target(kind: str, n_gas: int, n_tau: int, dtype) -> str:
    r"""The name of the :func:`jax.ffi.ffi_call` target that runs sweep ``kind`` on XLA's
    buffers (:mod:`operators.rte.xla_ffi`), its handler compiled on first use (2–6 s, or loaded
    from Numba's disk cache).

    Every sweep takes, in this order: ``coef`` (n_intervals, n_rows, n_eta), the tables'
    coefficients (:attr:`operators.rte.tables.RTETables.coef`); ``index`` (n_rays, n_seg),
    int32, each segment's temperature interval; ``amount`` (n_rays, n_seg, n_tau), the amounts
    :math:`X_s \Delta s / T` (m/K) per gas, then the soot's :math:`f_v \Delta s` (m);
    ``offset`` (n_rays, n_seg), the offset :math:`u \in [0, 1]` in the interval;
    ``n_segments`` (n_rays,), int32, each ray's segments (those after are padding); ``order``
    (n_rays,), int32, the rays longest first (so that the cores' last rays are short ones).
    Floats in ``dtype``, radiances in W/(m²·sr·cm⁻¹). Then:

    ``"forward"``
        ``background`` (n_rays or 1, n_eta), the radiance behind each ray (one row: behind
        every ray) → the radiance (n_rays, n_eta),
        :math:`I = \sum_k B_k (1 - t_k) P_k + \tau_\mathrm{ray} I_\mathrm{bg}`.
    ``"forward_mode"``
        ``background``, ``d_amount``, ``d_offset`` (tangents shaped as ``amount`` and
        ``offset``), ``d_background`` (shaped as ``background``) → the radiance and its
        tangent: with :math:`D_k = \sum_{m<k} \dot\tau_m` the tangent of the optical depth in
        front of segment :math:`k` (:math:`\dot P_k = -P_k D_k`),
        :math:`\dot I = \sum_k P_k [(1 - t_k)(\dot B_k - B_k D_k) + t_k B_k \dot\tau_k]
        + \tau_\mathrm{ray} (\dot I_\mathrm{bg} - D_n I_\mathrm{bg})`,
        :math:`\dot\tau_k = \sum_s \dot a_s \tilde\sigma_s + \dot u\,\partial_u\tau`,
        :math:`\dot B_k = \dot u\,\partial_u \tilde B`.
    ``"reverse"``
        ``radiance`` and ``cotangent`` (n_rays, n_eta), the kernel's radiance (background
        included) and its cotangent → ``d_weights`` (n_rays, n_seg, n_tau + 1), the
        cotangents of the amounts, then of the offset (per segment, the sums over wavenumber
        of :math:`g_\tau` times each row of :math:`\tau`, and of
        :math:`g_\tau\,\partial\tau/\partial u + g_B\,\partial B/\partial u`; zero on
        padding), and each ray's transmittance :math:`\tau_\mathrm{ray}` (n_rays or 0, n_eta;
        asked for with 0 rows where no background needs its cotangent).

    Parameters
    ----------
    kind : {"forward", "forward_mode", "reverse"}
        The sweep.
    n_gas, n_tau : int
        Absorbing gases, and rows of the optical depth (``n_tau - n_gas`` is 1 with soot,
        else 0).
    dtype : {"float32", "float64"}
        The floats' dtype.

    Raises
    ------
    ValueError
        For an unknown kind or dtype, or more than one soot row.
    """
    if kind not in KINDS:
        raise ValueError(f"unknown sweep {kind!r}; choose one of {KINDS}")
    dtype = np.dtype(dtype).name
    module = compiled_sweeps(int(n_gas), int(n_tau), dtype)
    numba.get_num_threads()  # starts Numba's threads, whose symbols a cached handler links to
    handler = numba.cfunc(HANDLER, cache=True)(getattr(module, f"{kind}_handler"))
    return ffi_target(f"invflame_{kind}_{n_gas}_gases_{n_tau}_rows_{dtype}", handler)
