#!/usr/bin/env python3
"""How a stage's checkpoints do on the bars its gate does not see: the robustness sweeps from starts the
gate never flew, the same sweeps with the bars' own seed, and the closed-loop identification; or, with
--stroke, how each one strokes the segments of the longitudinal reference.

    scripts/checkpoint-scan.py --out DIR STAGE_DIR [--every 50] [--from 0] [--jobs N] [--extra POLICY ...] [--stroke]

For every checkpoint `STAGE_DIR/checkpoints/iter_*.safetensors` at a multiple of --every from iteration
--from on (and every --extra policy file): longitudinal with all five fluid coefficients x[0.7, 1.3] and
lateral under Table III at once, each from 200 held-out starts (`--seed 1000`) and from the robustness bars'
100 starts (`--seed 1`), and `flapper sysid`'s validation fit per axis. Jobs run side by side, one thread
each (--jobs, default one per core). With --stroke, only `flapper modes` (one flight from the exact start,
about a second): per segment (cruise, climb, glide, dive) the flap's amplitude, its fundamental, the share of
its energy in that fundamental (near 1: a steady rhythm), the mean net power and the glide fraction.
Writes DIR/scan.csv and prints it. The flapper binary: $FLAPPER, else target/release/flapper. A checkpoint
can be flown directly (no export needed).
"""

import argparse
import csv
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from flapper_outputs import identified_fits, modes_segments, one_thread_env

HELD_OUT_SEED, HELD_OUT_EPISODES = 1000, 200
BAR_SEED, BAR_EPISODES = 1, 100
# --stroke: longitudinal's segments as `flapper modes` names them, and the figures taken from each.
SEGMENTS = ["cruise", "climb", "glide", "dive"]
STROKE_FIGURES = ["flap_amplitude_deg", "flap_fundamental_hz", "flap_energy_fraction", "mean_power_w", "glide_fraction"]


def stroke_jobs_for(flapper, name, policy, out):
    """`flapper modes` for one policy: (output folder, argument list)."""
    modes = out / name / "modes"
    return [(modes, [flapper, "modes", "--policy", str(policy), "--out", str(modes)], True)]


def stroke_row(name, folder):
    """One row of the --stroke table from `flapper modes`' modes.json; a checkpoint that does not fly the
    reference to its end gets empty figures and `flapper modes`' reason in `flown`."""
    modes = folder / "modes"
    if not (modes / "modes.json").exists():
        reason = modes.with_suffix(".txt").read_text().strip().splitlines()[-1]
        return {"policy": name, "flown": reason,
                **{f"{tag}_{figure}": "" for tag in SEGMENTS for figure in STROKE_FIGURES}}
    row = {"policy": name, "flown": "yes"}
    for s in modes_segments(modes).values():
        for figure in STROKE_FIGURES:
            row[f"{s['segment']}_{figure}"] = round(s[figure], 1 if figure == "flap_amplitude_deg" else 2)
    return row


def jobs_for(flapper, name, policy, out):
    """The flapper commands for one policy: (output folder, argument list)."""
    def robustness(tag, reference, sweep, seed, episodes):
        folder = out / name / tag
        args = [flapper, "robustness", "--policy", str(policy), "--reference", reference, "--sweeps", sweep,
                "--episodes", str(episodes), "--seed", str(seed), "--out", str(folder)]
        return folder, args + (["--ranges", "0.3"] if sweep == "fluid" else [])

    sysid = out / name / "sysid"
    jobs = [
        robustness("lon-fluid-held-out", "longitudinal", "fluid", HELD_OUT_SEED, HELD_OUT_EPISODES),
        robustness("lat-table3-held-out", "lateral", "table3", HELD_OUT_SEED, HELD_OUT_EPISODES),
        robustness("lon-fluid-bar", "longitudinal", "fluid", BAR_SEED, BAR_EPISODES),
        robustness("lat-table3-bar", "lateral", "table3", BAR_SEED, BAR_EPISODES),
        (sysid, [flapper, "sysid", "--policy", str(policy), "--out", str(sysid)]),
    ]
    return [(folder, args, False) for folder, args in jobs]


def run(job):
    """Runs one flapper command, its output to FOLDER.txt; stops the scan if it fails, unless it may (a
    checkpoint that cannot fly a reference is a finding of --stroke, not an error)."""
    folder, args, may_fail = job
    folder.parent.mkdir(parents=True, exist_ok=True)
    log = folder.with_suffix(".txt")
    with open(log, "w") as f:
        done = subprocess.run(args, stdout=f, stderr=subprocess.STDOUT, env=one_thread_env())
    if done.returncode != 0 and not may_fail:
        sys.exit(f"checkpoint-scan: '{' '.join(args)}' failed (exit {done.returncode}); its output: {log}")


def all_five_percent(folder):
    """Success (%) with all five fluid coefficients at r = 0.3, from robustness_fluid.csv."""
    with open(folder / "robustness_fluid.csv") as f:
        for row in csv.DictReader(f):
            if row["coefficient"] == "all" and abs(float(row["range"]) - 0.3) < 1e-9:
                return 100.0 * float(row["success_rate"])
    sys.exit(f"checkpoint-scan: no 'all' row at range 0.3 in {folder / 'robustness_fluid.csv'}")


def table3_percent(folder):
    text = (folder.with_suffix(".txt")).read_text()
    match = re.search(r"at once: (\d+)/(\d+)", text)
    if not match:
        sys.exit(f"checkpoint-scan: no Table III result in {folder.with_suffix('.txt')}")
    return 100.0 * int(match.group(1)) / int(match.group(2))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("stage_dir", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--every", type=int, default=50)
    parser.add_argument("--from", dest="start", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=os.cpu_count())
    parser.add_argument("--extra", type=Path, nargs="*", default=[])
    parser.add_argument("--stroke", action="store_true",
                        help="fly `flapper modes` only: the stroke per segment of longitudinal")
    a = parser.parse_args()
    if a.every < 1:
        sys.exit(f"checkpoint-scan: --every must be at least 1, not {a.every}")
    flapper = os.environ.get("FLAPPER", "target/release/flapper")
    if not Path(flapper).exists():
        sys.exit(f"checkpoint-scan: no flapper binary at '{flapper}' (build with `cargo build --release` or set $FLAPPER)")
    checkpoints = sorted((a.stage_dir / "checkpoints").glob("iter_*.safetensors"))
    policies = [(f"iter_{int(p.stem[5:]):06d}", p) for p in checkpoints
                if int(p.stem[5:]) >= a.start and int(p.stem[5:]) % a.every == 0]
    policies += [(p.stem if p.stem != "policy" else p.parent.name, p) for p in a.extra]
    if not policies:
        sys.exit(f"checkpoint-scan: no checkpoint in '{a.stage_dir / 'checkpoints'}' from iteration {a.start} at a multiple of {a.every}")
    if a.out.exists() and any(a.out.iterdir()):
        sys.exit(f"checkpoint-scan: '{a.out}' is not empty; give a new --out")
    make_jobs = stroke_jobs_for if a.stroke else jobs_for
    jobs = [job for name, policy in policies for job in make_jobs(flapper, name, policy, a.out)]
    with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        list(pool.map(run, jobs))
    rows = []
    for name, _ in policies:
        d = a.out / name
        if a.stroke:
            rows.append(stroke_row(name, d))
            continue
        fits = identified_fits(d / "sysid")
        rows.append({
            "policy": name,
            "lon_fluid_held_out_percent": all_five_percent(d / "lon-fluid-held-out"),
            "lon_fluid_bar_percent": all_five_percent(d / "lon-fluid-bar"),
            "lat_table3_held_out_percent": table3_percent(d / "lat-table3-held-out"),
            "lat_table3_bar_percent": table3_percent(d / "lat-table3-bar"),
            **{f"sysid_fit_{axis}_percent": round(fit, 1) for axis, fit in fits.items()},
        })
    with open(a.out / "scan.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(",".join(rows[0]))
    for row in rows:
        print(",".join(str(v) for v in row.values()))
    print(f"wrote {a.out / 'scan.csv'}")


if __name__ == "__main__":
    main()
