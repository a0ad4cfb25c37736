#!/usr/bin/env python3
"""Which measured controllers meet which of the efficient-bird issue's bars that `flapper frontier` measures:
the frontier between slow flight (bar 5) and efficiency (bars 1-3), from frontier.csv files.

    scripts/frontier-bars.py docs/energy-frontier.csv                      the points measured in experiments
    scripts/frontier-bars.py run/report/frontier/frontier.csv             the report's controllers and those points

Bars, from each row's longitudinal and level-3 m/s columns (`flapper frontier --episodes 100 --seed 11`):
1 energy per metre on longitudinal at most 1.5 x the scripted gait's; 2 glide fraction at least 0.5; 3 cruise flap
within 4-6 Hz; 5 level 3.0 m/s completed in at least 95% of its episodes with RMS at most 0.5 m. (Bar 1's "every
named reference at most 3 x" and bar 4's tracking need `flapper eval`, which frontier.csv does not hold.)
Prints, per set of bars, how many rows meet it and the row among them with the smallest level-3 m/s RMS error
(of those completing it in 95% of episodes), then every row that meets bar 5.
"""

import argparse
import csv
import sys
from pathlib import Path

from flapper_outputs import frontier_bars_met, level3_held

SETS = [("1", "energy"), ("2", "glide"), ("3", "flap"), ("1+2", "energy glide"), ("1+3", "energy flap"),
        ("1+2+3", "energy glide flap"), ("5", "level3"), ("1+5", "energy level3"), ("2+5", "glide level3"),
        ("3+5", "flap level3"), ("1+2+3+5", "energy glide flap level3")]


def number(text):
    """A CSV cell as a float; None when empty or not a number."""
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def judge(row):
    """The bars one frontier.csv row meets, and its level-3 m/s figures."""
    energy, glide, flap = number(row.get("energy_ratio")), number(row.get("glide_fraction")), number(row.get("cruise_flap_hz"))
    rms, completed, episodes = (number(row.get(k)) for k in ("level3_rms_m", "level3_completed", "level3_episodes"))
    holds_level3 = level3_held(completed, episodes)
    met = frontier_bars_met(energy, glide, flap, (completed, episodes, rms))
    return {"label": row.get("label", ""), "met": met, "energy": energy, "glide": glide, "flap": flap,
            "level3_rms": rms if holds_level3 else None}


def read_rows(paths):
    rows = []
    for path in paths:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            missing = {"label", "energy_ratio", "glide_fraction", "cruise_flap_hz", "level3_rms_m"} - set(reader.fieldnames or [])
            if missing:
                raise ValueError(f"{path}: not a frontier.csv (no column {', '.join(sorted(missing))})")
            rows.extend(judge(row) for row in reader)
    return rows


def shown(x, digits):
    return "-" if x is None else f"{x:.{digits}f}"


def table(rows):
    """The markdown table: per set of bars, the rows meeting it and the best level-3 m/s among them."""
    lines = ["| bars | rows meeting them | of those, the smallest level 3 m/s RMS (m) | that row | its energy ratio, glide, flap (Hz) |",
             "|---|---|---|---|---|"]
    for name, needs in SETS:
        meeting = [r for r in rows if set(needs.split()) <= r["met"]]
        flown = sorted((r for r in meeting if r["level3_rms"] is not None), key=lambda r: r["level3_rms"])
        if flown:
            b = flown[0]
            best = (shown(b["level3_rms"], 3), b["label"],
                    f"{shown(b['energy'], 2)} x, {shown(b['glide'], 2)}, {shown(b['flap'], 2)}")
        else:
            best = ("-", "-", "-")
        lines.append(f"| {name} | {len(meeting)} of {len(rows)} | {best[0]} | {best[1]} | {best[2]} |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("frontier_csv", nargs="+", type=Path, help="frontier.csv files (flapper frontier, docs/energy-frontier.csv)")
    args = parser.parse_args()
    try:
        rows = read_rows(args.frontier_csv)
    except (OSError, ValueError, csv.Error) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    print(table(rows))
    slow = [r for r in rows if "level3" in r["met"]]
    print(f"\nbar 5 met by {len(slow)} of {len(rows)}:")
    for r in slow:
        print(f"  {r['label']}: level 3 m/s {shown(r['level3_rms'], 3)} m, {shown(r['energy'], 2)} x, glide "
              f"{shown(r['glide'], 2)}, flap {shown(r['flap'], 2)} Hz")
    return 0


if __name__ == "__main__":
    sys.exit(main())
