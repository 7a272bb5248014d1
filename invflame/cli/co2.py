"""``invflame co2``: generate the ¹²C¹⁶O₂ line list and validate it against a HITRAN slice."""

from __future__ import annotations

import argparse
from pathlib import Path

from invflame.errors import ConfigError

DEFAULT_REFERENCE = (
    Path(__file__).resolve().parents[2]
    / ".."
    / "shared"
    / "linedata"
    / "CO2_HITRAN_691.4-692.7_validation.par"
)


def add_parser(subparsers) -> None:
    """Register ``co2 validate`` and ``co2 write``."""
    parser = subparsers.add_parser(
        "co2",
        help="generated 12C16O2 line list (15 um nu2 band system)",
        description="Generate the 12C16O2 line list from published constants, write it as a "
        "HITRAN .par file, or compare it with a HITRAN reference slice.",
    )
    sub = parser.add_subparsers(dest="co2_command", required=True)

    validate = sub.add_parser(
        "validate",
        help="compare with a HITRAN CO2 slice (positions, intensities at 296/1000/1500 K)",
        description="Match generated lines to the reference by band, branch, J'' and e/f and "
        "print position errors, intensity ratios, unmatched lines and window totals.",
    )
    validate.add_argument(
        "--reference",
        type=Path,
        default=DEFAULT_REFERENCE,
        help="HITRAN 160-character .par file with 626 lines (default: "
        "../shared/linedata/CO2_HITRAN_691.4-692.7_validation.par beside the repository)",
    )
    validate.add_argument(
        "--nu-min", type=float, default=691.38, help="window start, cm-1 (default 691.38)"
    )
    validate.add_argument(
        "--nu-max", type=float, default=692.68, help="window end, cm-1 (default 692.68)"
    )
    validate.add_argument(
        "--rows", type=int, default=40, help="matched lines shown, strongest first (default 40)"
    )
    validate.set_defaults(func=run)

    write = sub.add_parser(
        "write",
        help="write the generated lines as a HITRAN .par file",
        description="Generate 12C16O2 lines in a window and write 160-character HITRAN records.",
    )
    write.add_argument("path", type=Path, help="output .par file (overwritten)")
    write.add_argument(
        "--nu-min", type=float, default=600.0, help="window start, cm-1 (default 600)"
    )
    write.add_argument("--nu-max", type=float, default=800.0, help="window end, cm-1 (default 800)")
    write.add_argument(
        "--j-max", type=int, default=120, help="highest lower-state J'' (default 120)"
    )
    write.add_argument(
        "--s-min",
        type=float,
        default=1e-30,
        help="drop lines weaker than this S(296 K), cm/molecule (default 1e-30)",
    )
    write.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``co2 validate`` or ``co2 write``; returns the exit status."""
    if args.co2_command == "validate":
        from invflame.spectroscopy.co2_validation import format_report, validate_against_par

        if not args.reference.is_file():
            raise FileNotFoundError(f"reference line file not found: {args.reference} (pass "
                                    "--reference PATH)")
        comparison = validate_against_par(args.reference, args.nu_min, args.nu_max)
        print(format_report(comparison, max_rows=args.rows))
        return 0
    from invflame.spectroscopy.co2_lines import generate_co2_lines
    from invflame.spectroscopy.linelist import write_par

    if not args.nu_min < args.nu_max:
        raise ConfigError(f"--nu-min {args.nu_min:g} must be below --nu-max {args.nu_max:g} "
                          "(cm-1)")
    lines = generate_co2_lines(args.nu_min, args.nu_max, J_max=args.j_max, S_min=args.s_min)
    if not len(lines):
        raise ConfigError(f"no generated CO2 line in {args.nu_min:g}-{args.nu_max:g} cm-1 "
                          f"(J'' <= {args.j_max}, S(296 K) >= {args.s_min:g}): {args.path} was "
                          "not written; the generated lines span about 345-1070 cm-1")
    write_par(lines, args.path)
    print(
        f"wrote {len(lines)} lines ({lines.nu.min():.4f}–{lines.nu.max():.4f} cm-1) to {args.path}"
    )
    return 0
