"""Spectral line lists and the HITRAN/HITEMP 160-character record format.

A :class:`LineList` holds one array per line parameter (structure of arrays). :func:`read_par`
streams a ``.par`` file in chunks, so a HITEMP file of millions of lines can be read filtered to a
wavenumber window without holding it in memory; :func:`write_par` writes records that
:func:`read_par` reads back to the printed precision.

Record layout (1-based columns, HITRAN2004 and later; Rothman et al. 2005, JQSRT 96, 139–204):
molecule 1–2, isotopologue 3, ν 4–15, S(296 K) 16–25, A 26–35, γ_air 36–40, γ_self 41–45,
E'' 46–55, n_air 56–59, δ_air 60–67, V' 68–82, V'' 83–97, Q' 98–112, Q'' 113–127,
uncertainty codes 128–133, references 134–145, line-mixing flag 146, g' 147–153, g'' 154–160.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from invflame.atomic_files import write_atomic
from invflame.errors import InputDataError

RECORD_LENGTH = 160

# Numeric fields: name -> (first column, last column) 1-based inclusive, dtype, write format.
_NUMERIC = {
    "molecule": (1, 2, int, "{:2d}"),
    "nu": (4, 15, float, "{:12.6f}"),
    "S296": (16, 25, float, "{:10.3E}"),
    "A": (26, 35, float, "{:10.3E}"),
    "gamma_air": (36, 40, float, "{:5.4f}"),
    "gamma_self": (41, 45, float, "{:5.3f}"),
    "E_lower": (46, 55, float, "{:10.4f}"),
    "n_air": (56, 59, float, "{:4.2f}"),
    "delta_air": (60, 67, float, "{:8.6f}"),
    "g_upper": (147, 153, float, "{:7.1f}"),
    "g_lower": (154, 160, float, "{:7.1f}"),
}
_QUANTA = {
    "V_upper": (68, 82),
    "V_lower": (83, 97),
    "Q_upper": (98, 112),
    "Q_lower": (113, 127),
}
#: Fields that must not be negative (intensity, Einstein A, half widths, statistical weights).
_NON_NEGATIVE = ("S296", "A", "gamma_air", "gamma_self", "g_upper", "g_lower")
_ISO_COLUMN = 3
# Isotopologue numbers above 9 are written as one character: 0 = 10, A = 11, B = 12, ...
_ISO_CHARS = "123456789" + "0" + "ABCDEFGHIJKLMNOPQRSTUVWXYZ"


@dataclass(frozen=True, eq=False)
class LineList:
    """Spectral lines as a structure of arrays (all 1-D, one entry per line).

    Attributes
    ----------
    molecule, isotopologue : ndarray of int
        HITRAN molecule and local isotopologue numbers (H2O = 1, CO2 = 2, CH4 = 6).
    nu : ndarray of float
        Line position at zero pressure, cm⁻¹.
    S296 : ndarray of float
        Line intensity at 296 K, cm⁻¹/(molecule·cm⁻²) = cm/molecule, scaled by the natural
        isotopologue abundance (HITRAN convention).
    A : ndarray of float
        Einstein A coefficient, s⁻¹.
    gamma_air, gamma_self : ndarray of float
        Air- and self-broadened Lorentz half width at half maximum at 296 K, cm⁻¹/atm.
    E_lower : ndarray of float
        Lower-state energy, cm⁻¹.
    n_air : ndarray of float
        Temperature exponent of ``gamma_air`` (dimensionless).
    delta_air : ndarray of float
        Air pressure shift of the line position at 296 K, cm⁻¹/atm.
    V_upper, V_lower, Q_upper, Q_lower : ndarray of str
        Upper/lower global (vibrational) and local (rotational) quanta, the 15-character fields
        exactly as in the record.
    g_upper, g_lower : ndarray of float
        Upper and lower statistical weights.
    """

    molecule: np.ndarray
    isotopologue: np.ndarray
    nu: np.ndarray
    S296: np.ndarray
    A: np.ndarray
    gamma_air: np.ndarray
    gamma_self: np.ndarray
    E_lower: np.ndarray
    n_air: np.ndarray
    delta_air: np.ndarray
    V_upper: np.ndarray
    V_lower: np.ndarray
    Q_upper: np.ndarray
    Q_lower: np.ndarray
    g_upper: np.ndarray
    g_lower: np.ndarray

    def __post_init__(self):
        lengths = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in _QUANTA:
                array = np.asarray(value, dtype="U15")
            elif f.name in ("molecule", "isotopologue"):
                array = np.asarray(value, dtype=np.int64)
            else:
                array = np.asarray(value, dtype=np.float64)
            if array.ndim != 1:
                raise ValueError(f"LineList.{f.name} must be 1-D, got shape {array.shape}")
            object.__setattr__(self, f.name, array)
            lengths[f.name] = array.size
        if len(set(lengths.values())) > 1:
            raise ValueError(f"LineList arrays must all have the same length, got {lengths}")

    def __len__(self) -> int:
        return self.nu.size

    def __repr__(self) -> str:
        if len(self) == 0:
            return "LineList(0 lines)"
        molecules = sorted(set(self.molecule.tolist()))
        return (
            f"LineList({len(self)} lines, molecules {molecules}, "
            f"{self.nu.min():.4f}–{self.nu.max():.4f} cm⁻¹)"
        )

    def select(self, mask) -> LineList:
        """Lines where ``mask`` is true (boolean mask or integer indices)."""
        return LineList(**{f.name: getattr(self, f.name)[mask] for f in fields(self)})

    def window(self, nu_min: float, nu_max: float) -> LineList:
        """Lines with ``nu_min <= nu <= nu_max`` (cm⁻¹)."""
        if nu_min > nu_max:
            raise ValueError(f"window needs nu_min <= nu_max, got {nu_min} > {nu_max}")
        return self.select((self.nu >= nu_min) & (self.nu <= nu_max))

    @classmethod
    def concatenate(cls, lists) -> LineList:
        """One line list holding the lines of all ``lists``, in order."""
        lists = list(lists)
        if not lists:
            return cls.empty()
        return cls(
            **{f.name: np.concatenate([getattr(x, f.name) for x in lists]) for f in fields(cls)}
        )

    @classmethod
    def empty(cls) -> LineList:
        """A line list with no lines."""
        return cls(**{f.name: [] for f in fields(cls)})


def _columns(block: np.ndarray, first: int, last: int) -> np.ndarray:
    """Bytes strings of columns ``first..last`` (1-based inclusive) of an (n, 160) uint8 block."""
    width = last - first + 1
    return np.ascontiguousarray(block[:, first - 1 : last]).view(f"S{width}").ravel()


def _parse_numeric(
    block: np.ndarray, name: str, path: Path, line_numbers: np.ndarray
) -> np.ndarray:
    first, last, dtype, _ = _NUMERIC[name]
    text = _columns(block, first, last)
    try:
        return text.astype(dtype)
    except ValueError:
        for number, item in zip(line_numbers, text, strict=True):
            try:
                dtype(item.decode("ascii", errors="replace"))
            except ValueError:
                raise InputDataError(
                    f"{path}: line {number}: field {name} (columns {first}-{last}) "
                    f"is not a valid {dtype.__name__}: {item.decode('ascii', errors='replace')!r}"
                ) from None
        raise


def _parse_isotopologue(block: np.ndarray, path: Path, line_numbers: np.ndarray) -> np.ndarray:
    codes = _columns(block, _ISO_COLUMN, _ISO_COLUMN)
    lookup = np.zeros(256, dtype=np.int64)
    for number, char in enumerate(_ISO_CHARS, start=1):
        lookup[ord(char)] = number
    iso = lookup[block[:, _ISO_COLUMN - 1]]
    bad = np.flatnonzero(iso == 0)
    if bad.size:
        raise InputDataError(
            f"{path}: line {line_numbers[bad[0]]}: isotopologue code (column 3) must be one of "
            f"{_ISO_CHARS!r}, got {codes[bad[0]].decode('ascii', errors='replace')!r}"
        )
    return iso


def _parse_block(block: np.ndarray, path: Path, line_numbers: np.ndarray, nu_range) -> dict:
    nu = _parse_numeric(block, "nu", path, line_numbers)
    if nu_range is not None:
        keep = (nu >= nu_range[0]) & (nu <= nu_range[1])
        block, line_numbers, nu = block[keep], line_numbers[keep], nu[keep]
    columns = {"nu": nu, "isotopologue": _parse_isotopologue(block, path, line_numbers)}
    for name in _NUMERIC:
        if name != "nu":
            columns[name] = _parse_numeric(block, name, path, line_numbers)
        _check_values(columns[name], name, path, line_numbers)
    for name, (first, last) in _QUANTA.items():
        columns[name] = _columns(block, first, last).astype("U15")
    return columns


def _check_values(values: np.ndarray, name: str, path: Path, line_numbers: np.ndarray) -> None:
    """Refuse NaN or infinite numbers, and negative ones in :data:`_NON_NEGATIVE` fields."""
    bad = ~np.isfinite(values) if values.dtype.kind == "f" else np.zeros(values.shape, bool)
    if name in _NON_NEGATIVE:
        bad |= values < 0
    if bad.any():
        first, last = _NUMERIC[name][:2]
        i = int(np.flatnonzero(bad)[0])
        allowed = "a finite number >= 0" if name in _NON_NEGATIVE else "a finite number"
        raise InputDataError(
            f"{path}: line {line_numbers[i]}: field {name} (columns {first}-{last}) must be "
            f"{allowed}, got {float(values[i]):g} ({int(bad.sum())} such record(s) in this "
            "chunk); fix or remove the record"
        )


def _chunk_to_block(lines: list[bytes], path: Path, first_line: int):
    """Check record lengths and ASCII; return the (n, 160) uint8 block and 1-based line numbers."""
    records, numbers = [], []
    for offset, raw in enumerate(lines):
        record = raw.rstrip(b"\r\n")
        if not record.strip():
            continue
        if len(record) != RECORD_LENGTH:
            raise InputDataError(
                f"{path}: line {first_line + offset}: record has {len(record)} characters, "
                f"expected {RECORD_LENGTH} (HITRAN 160-character format)"
            )
        records.append(record)
        numbers.append(first_line + offset)
    block = np.frombuffer(b"".join(records), dtype=np.uint8).reshape(len(records), RECORD_LENGTH)
    non_ascii = np.argwhere(block > 127)
    if non_ascii.size:
        row, column = non_ascii[0]
        raise InputDataError(
            f"{path}: line {numbers[row]}: column {column + 1} holds the non-ASCII byte "
            f"0x{block[row, column]:02x}; a .par record is 160 ASCII characters"
        )
    return block, np.asarray(numbers, dtype=np.int64)


def read_par(path, nu_range=None, chunk_lines: int = 200_000) -> LineList:
    """Read a HITRAN/HITEMP 160-character ``.par`` file.

    Parameters
    ----------
    path : str or Path
        The ``.par`` file.
    nu_range : (float, float), optional
        Keep only lines with ``nu_range[0] <= nu <= nu_range[1]`` (cm⁻¹). Without it, all lines.
    chunk_lines : int
        Records parsed at a time; memory use is bounded by this, not by the file size.

    Returns
    -------
    LineList
        The lines in file order.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    ValueError
        On a malformed record; the message names the file, the 1-based line number and the
        field that is wrong. Blank lines are skipped.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"line list file not found: {path}")
    if chunk_lines < 1:
        raise ValueError(f"chunk_lines must be a positive integer, got {chunk_lines}")
    if nu_range is not None:
        nu_range = (float(nu_range[0]), float(nu_range[1]))
        if nu_range[0] > nu_range[1]:
            raise ValueError(f"nu_range must be (nu_min, nu_max) with nu_min <= nu_max: {nu_range}")
    parts = []
    first_line = 1
    with path.open("rb") as stream:
        while True:
            lines = list(itertools.islice(stream, chunk_lines))
            if not lines:
                break
            block, numbers = _chunk_to_block(lines, path, first_line)
            first_line += len(lines)
            if numbers.size:
                parts.append(LineList(**_parse_block(block, path, numbers, nu_range)))
    return LineList.concatenate(parts)


def _format_fixed(value: float, fmt: str, width: int, name: str) -> str:
    """Format ``value`` into exactly ``width`` characters, dropping a leading zero if needed."""
    text = fmt.format(value)
    if len(text) > width:
        text = text.replace("0.", ".", 1) if text.lstrip("-").startswith("0.") else text
    if len(text) != width:
        raise ValueError(f"{name} = {value!r} does not fit the {width}-character HITRAN field")
    return text


def _format_record(lines: LineList, i: int) -> str:
    def number(name):
        first, last, _, fmt = _NUMERIC[name]
        return _format_fixed(getattr(lines, name)[i], fmt, last - first + 1, name)

    iso = int(lines.isotopologue[i])
    if not 1 <= iso <= len(_ISO_CHARS):
        raise ValueError(f"isotopologue {iso} cannot be written in the one-character field")
    quanta = "".join(f"{getattr(lines, name)[i]:<15.15s}" for name in _QUANTA)
    record = (
        number("molecule")
        + _ISO_CHARS[iso - 1]
        + "".join(
            number(name)
            for name in ("nu", "S296", "A", "gamma_air", "gamma_self", "E_lower", "n_air")
        )
        + number("delta_air")
        + quanta
        + " " * 6  # uncertainty codes: not kept in a LineList
        + " " * 12  # references
        + " "  # line-mixing flag
        + number("g_upper")
        + number("g_lower")
    )
    return record


def write_par(lines: LineList, path) -> None:
    """Write ``lines`` as 160-character HITRAN records.

    The uncertainty, reference and line-mixing columns are left blank (a :class:`LineList` does
    not hold them). The file is written to a temporary file beside ``path`` and renamed, so a
    reader never sees a partial file.

    Parameters
    ----------
    lines : LineList
    path : str or Path
        Destination ``.par`` file (overwritten).

    Raises
    ------
    ValueError
        If a value does not fit its fixed-width field.
    """
    records = "".join(_format_record(lines, i) + "\n" for i in range(len(lines)))
    write_atomic(path, lambda stream: stream.write(records.encode("ascii")))
