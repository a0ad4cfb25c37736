#!/usr/bin/env python3
"""Several short fine-tunes side by side: one `flapper train` config, a list of variants (keys changed),
one starting checkpoint, every variant trained at once on its own threads, then every checkpoint measured.
Made for a many-core machine, where eight 2-thread runs train as fast as one does on two cores.

    scripts/train-variants.py --config TRAIN.toml --init-from CHECKPOINT --variants VARIANTS.txt --out DIR
        [--iterations N] [--jobs 8] [--threads 2] [--frontier-last 2] [--time-limit S]

TRAIN.toml is a `flapper train` config (a curriculum run writes one per stage: RUN/stageK/config.toml).
VARIANTS.txt holds one variant a line, a name and then `table.key=value` edits of that config
(`#` starts a comment), for example

    half-dive   task.reward.position_dive_gain=1.0
    kernel07    task.reward.position_dive_gain=0.0  task.reward.position_scale_m=0.7
    low-noise   runner.init_from_noise_std=0.3

A key the config does not write is added to its table. Each variant trains with `flapper train --config
DIR/NAME.toml --init-from CHECKPOINT --out DIR/NAME` (its `runner.threads` set to --threads; threads change
no bit of training), for --iterations or until --time-limit seconds have passed (the checkpoints written by
then are kept). Then each checkpoint is exported (DIR/NAME/policies/iter_K.safetensors) and measured with one
thread per measurement: `flapper sysid` (the identified fit per axis), `flapper modes` (the glide fraction and
cruise flap from the exact start) and, for each variant's last --frontier-last checkpoints, `flapper frontier
--episodes 100 --seed 11` (longitudinal RMS and energy ratio, glide fraction, cruise flap, level 3 m/s on 100
starts). Writes DIR/variants.csv and prints it as a table; exits 1 if a variant did not train (its line
says why), 2 on bad arguments or a bad variants file (before anything trains). The flapper binary: $FLAPPER,
else target/release/flapper.
"""

import argparse
import csv
import os
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor, wait
from pathlib import Path

from flapper_outputs import frontier_point, identified_fits, modes_segments

FLAPPER = os.environ.get("FLAPPER", "target/release/flapper")
NAME = re.compile(r"^[A-Za-z0-9_.-]+$")
COLUMNS = [
    "variant", "iteration", "fit_x", "fit_y", "fit_z", "glide_exact_start", "cruise_flap_hz_exact_start",
    "longitudinal_completed", "longitudinal_rms_m", "energy_ratio", "glide_fraction", "cruise_flap_hz",
    "level3_completed", "level3_rms_m",
]


def fail(message):
    print(f"error: {message}", file=sys.stderr)
    sys.exit(2)


def read_variants(path):
    """[(name, [(table, key, value)])] from the variants file; a bad line stops with its number."""
    variants = []
    for number, line in enumerate(Path(path).read_text().splitlines(), 1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        name, edits = words[0], []
        if not NAME.match(name) or any(name == v[0] for v in variants):
            fail(f"{path}, line {number}: '{name}' is not a new variant name (letters, digits, '_', '.', '-')")
        for word in words[1:]:
            key, sep, value = word.partition("=")
            table, dot, leaf = key.rpartition(".")
            if not sep or not dot or not value or not leaf:
                fail(f"{path}, line {number}: '{word}' is not table.key=value (e.g. task.reward.position_dive_gain=1.0)")
            edits.append((table, leaf, value))
        if not edits:
            fail(f"{path}, line {number}: variant '{name}' changes nothing")
        variants.append((name, edits))
    if not variants:
        fail(f"{path} holds no variant")
    return variants


def edited(config_text, edits):
    """The config with each `[table] key = value` set: the key's line replaced, or added to its table."""
    lines = config_text.split("\n")
    for table, key, value in edits:
        try:
            start = lines.index(f"[{table}]")
        except ValueError:
            raise ValueError(f"the config has no [{table}] table") from None
        end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("[")), len(lines))
        hit = next((i for i in range(start + 1, end) if lines[i].split("=")[0].strip() == key), None)
        if hit is None:
            lines.insert(start + 1, f"{key} = {value}")
        else:
            lines[hit] = f"{key} = {value}"
    return "\n".join(lines)


def run(args, log=None, threads=None):
    env = dict(os.environ)
    if threads is not None:
        env["RAYON_NUM_THREADS"] = str(threads)
    with open(log, "w") if log else open(os.devnull, "w") as out:
        return subprocess.run(args, stdout=out, stderr=subprocess.STDOUT, env=env).returncode


def train(out, name, init_from, iterations, deadline):
    args = [FLAPPER, "train", "--config", str(out / f"{name}.toml"), "--init-from", init_from, "--out",
            str(out / name), "--iterations", str(iterations)]
    with open(out / f"{name}.log", "w") as log:
        process = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT)
        try:
            return process.wait(timeout=None if deadline is None else max(1.0, deadline - time.time()))
        except subprocess.TimeoutExpired:
            process.terminate()
            process.wait()
            return "stopped at the time limit"


def progress(log):
    """The latest `it N/M` a `flapper train` log shows; 'starting' before its first, 'waiting' before the log."""
    try:
        found = re.findall(r"\bit (\d+/\d+)", log.read_text())
    except OSError:
        return "waiting"
    return f"it {found[-1]}" if found else "starting"


def measure(folder, frontier):
    """Fly sysid, modes and (if asked) frontier on an exported policy, one thread each. A measurement that
    fails leaves its cells empty; its log is in the policy's folder (sysid.log, modes.log, frontier.log)."""
    policy = folder / "policy.safetensors"
    row = {}
    if run([FLAPPER, "sysid", "--policy", str(policy), "--out", str(folder / "sysid")], folder / "sysid.log", 1) == 0:
        row.update({f"fit_{axis}": f"{fit:.1f}" for axis, fit in identified_fits(folder / "sysid").items()})
    if run([FLAPPER, "modes", "--policy", str(policy), "--out", str(folder / "modes")], folder / "modes.log", 1) == 0:
        segments = modes_segments(folder / "modes")
        row["glide_exact_start"] = f"{segments['glide']['glide_fraction']:.2f}"
        row["cruise_flap_hz_exact_start"] = f"{segments['cruise']['flap_fundamental_hz']:.2f}"
    if frontier:
        args = [FLAPPER, "frontier", "--policy", str(policy), "--label", folder.name, "--episodes", "100",
                "--seed", "11", "--out", str(folder / "frontier")]
        if run(args, folder / "frontier.log", 1) == 0:
            first = frontier_point(folder / "frontier")
            for key in ["longitudinal_completed", "longitudinal_rms_m", "energy_ratio", "glide_fraction",
                        "cruise_flap_hz", "level3_completed", "level3_rms_m"]:
                row[key] = first[key]
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", required=True, help="a flapper train config (TOML)")
    parser.add_argument("--init-from", required=True, help="the checkpoint or policy every variant starts from")
    parser.add_argument("--variants", required=True, help="one variant a line: NAME table.key=value ...")
    parser.add_argument("--out", required=True, type=Path, help="a new folder for the runs and variants.csv")
    parser.add_argument("--iterations", type=int, default=400, help="PPO iterations per variant (400)")
    parser.add_argument("--jobs", type=int, default=8, help="variants trained at once (8)")
    parser.add_argument("--threads", type=int, default=2, help="threads per variant (2)")
    parser.add_argument("--frontier-last", type=int, default=2, help="checkpoints per variant measured by frontier (2)")
    parser.add_argument("--time-limit", type=float, help="stop training after this many seconds, keep its checkpoints")
    args = parser.parse_args()
    for flag, value in [("--iterations", args.iterations), ("--jobs", args.jobs), ("--threads", args.threads)]:
        if value < 1:
            fail(f"{flag} must be at least 1 (got {value})")
    if args.frontier_last < 0:
        fail(f"--frontier-last must be 0 or more (got {args.frontier_last})")
    for flag, path in [("--config", args.config), ("--init-from", args.init_from), ("--variants", args.variants)]:
        if not Path(path).is_file():
            fail(f"{flag} '{path}' is not a file")
    if not Path(FLAPPER).is_file():
        fail(f"no flapper binary at '{FLAPPER}' (build it with `cargo build --release -p flapper-cli`, or set FLAPPER)")
    if args.out.exists():
        fail(f"--out '{args.out}' exists; give a new folder (nothing in it is overwritten)")
    variants = read_variants(args.variants)
    base = Path(args.config).read_text()
    texts = {}
    for name, edits in variants:
        try:
            texts[name] = edited(base, edits + [("runner", "threads", str(args.threads))])
        except ValueError as e:
            fail(f"{args.variants}, variant '{name}': {e} ({args.config})")
    args.out.mkdir(parents=True)
    for name, text in texts.items():
        (args.out / f"{name}.toml").write_text(text)

    deadline = None if args.time_limit is None else time.time() + args.time_limit
    print(f"training {len(variants)} variants of {args.config} from {args.init_from}, {args.jobs} at once on "
          f"{args.threads} threads each, {args.iterations} iterations", flush=True)
    with ThreadPoolExecutor(args.jobs) as pool:
        futures = {n: pool.submit(train, args.out, n, args.init_from, args.iterations, deadline) for n in texts}
        started = time.time()
        while wait(futures.values(), timeout=60).not_done:
            print(f"  {time.time() - started:.0f} s: " + ", ".join(f"{n} {progress(args.out / f'{n}.log')}" for n in texts),
                  flush=True)
        ends = {n: f.result() for n, f in futures.items()}
    for name, end in ends.items():
        if end == 0 or isinstance(end, str):
            print(f"  {name}: {'done' if end == 0 else end}")
        else:
            last = (args.out / f"{name}.log").read_text().strip().splitlines()[-1:] or ["no output"]
            print(f"  {name}: flapper train exited {end}: {last[0]} ({args.out / name}.log)")

    tasks = []
    for name in texts:
        checkpoints = sorted((args.out / name / "checkpoints").glob("iter_*.safetensors"))
        for k, checkpoint in enumerate(checkpoints):
            iteration = int(checkpoint.stem.removeprefix("iter_"))
            folder = args.out / name / "policies" / f"{name}-{iteration}"
            folder.mkdir(parents=True)
            if run([FLAPPER, "export-policy", "--policy", str(checkpoint), "--out", str(folder / "policy.safetensors")]) != 0:
                print(f"  {checkpoint}: not exported (written as training stopped?)")
                continue
            tasks.append((name, iteration, folder, k >= len(checkpoints) - args.frontier_last))
    print(f"measuring {len(tasks)} checkpoints, {args.jobs * args.threads} at once", flush=True)
    with ThreadPoolExecutor(args.jobs * args.threads) as pool:
        futures = [pool.submit(measure, t[2], t[3]) for t in tasks]
        while pending := wait(futures, timeout=60).not_done:
            print(f"  measured {len(futures) - len(pending)} of {len(futures)}", flush=True)
        measured = [f.result() for f in futures]
    rows = [{"variant": t[0], "iteration": t[1], **m} for t, m in zip(tasks, measured)]
    with open(args.out / "variants.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    widths = [max(len(c), 6) for c in COLUMNS]
    print("  ".join(c.rjust(w) for c, w in zip(COLUMNS, widths)))
    for row in rows:
        print("  ".join(str(row.get(c, "")).rjust(w) for c, w in zip(COLUMNS, widths)))
    print(f"wrote {args.out / 'variants.csv'}")
    failed = [name for name, end in ends.items() if not (end == 0 or isinstance(end, str))]
    if failed:
        print(f"error: {len(failed)} of {len(ends)} variants did not train: {', '.join(failed)}", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
