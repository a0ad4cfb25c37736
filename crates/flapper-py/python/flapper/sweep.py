"""Seed studies and sweeps as Ray Tune trials: `python -m flapper.sweep SWEEP.toml --out DIR`.

Each trial runs `flapper curriculum` (or `flapper train`) in its own run folder, with one seed and one
variant of the config; Ray Tune schedules the trials (locally, or on a cluster with `--address auto`)
and receives each trial's progress (iteration, environment steps, mean return, validation score) as the
run's CSV files grow. At the end every finished trial's controller is flown on the sweep's evaluation
references, and DIR/results.csv (one row per trial: seed, environment steps, wall time, then per
reference `<name>_completed` out of its episodes and `<name>_rms_m`) and DIR/results.png compare them.

Running the same command again skips finished trials and continues interrupted ones (a flapper run
folder continues exactly where it stopped). The sweep file:

    command = "curriculum"              # or "train" (one `flapper train` config)
    config = "configs/curriculum.toml"  # relative to the sweep file
    seeds = [1, 2, 3]
    cpus_per_trial = 2                  # the threads each training uses

    [[variants]]                        # optional; without it one variant, "base"
    name = "kl-0.02"
    set = { "stages.2.ppo.desired_kl" = 0.02 }   # dotted keys; a number indexes a list (0-based): in a
                                                 # config that extends another, its own [[stages]] entries

    [evaluation]                        # optional
    references = ["cruise", "lateral"]
    episodes = 100
    seed = 11
"""

import argparse
import copy
import csv
import math
import os
import pathlib
import shutil
import subprocess
import sys
import time
import tomllib

DONE = "trial_done.txt"


class SweepError(Exception):
    """A sweep file or a trial that cannot run; the message says which and why."""


def load_sweep(path):
    path = pathlib.Path(path).resolve()
    try:
        sweep = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise SweepError(f"sweep file '{path}': {e}") from None
    known = {"command", "config", "seeds", "cpus_per_trial", "variants", "evaluation"}
    unknown = set(sweep) - known
    if unknown:
        raise SweepError(f"sweep file '{path}': unknown key(s) {', '.join(sorted(unknown))} (known: {', '.join(sorted(known))})")
    if sweep.get("command", "curriculum") not in ("curriculum", "train"):
        raise SweepError(f"sweep file '{path}': command must be \"curriculum\" or \"train\", got {sweep['command']!r}")
    seeds = sweep.get("seeds")
    if not seeds or not all(isinstance(s, int) and s >= 0 for s in seeds) or len(set(seeds)) != len(seeds):
        raise SweepError(f"sweep file '{path}': seeds must be a list of distinct non-negative integers, got {seeds!r}")
    if "config" not in sweep:
        raise SweepError(f"sweep file '{path}': needs config = \"FILE\" (the curriculum or training config)")
    config = (path.parent / sweep["config"]).resolve()
    if not config.is_file():
        raise SweepError(f"sweep file '{path}': config '{config}' does not exist")
    variants = sweep.get("variants", [{"name": "base"}])
    names = [v.get("name") for v in variants]
    if not all(isinstance(n, str) and n and n.replace("-", "").replace("_", "").replace(".", "").isalnum() for n in names):
        raise SweepError(f"sweep file '{path}': every variant needs a name of letters, digits, '-', '_' or '.', got {names!r}")
    if len(set(names)) != len(names):
        raise SweepError(f"sweep file '{path}': variant names repeat: {names!r}")
    cpus = sweep.get("cpus_per_trial", 2)
    if not (isinstance(cpus, int) and 1 <= cpus <= 1024):
        raise SweepError(f"sweep file '{path}': cpus_per_trial must be 1 to 1024, got {cpus!r}")
    return {
        "command": sweep.get("command", "curriculum"),
        "config": config,
        "seeds": seeds,
        "cpus_per_trial": cpus,
        "variants": variants,
        "evaluation": sweep.get("evaluation"),
        "origin": path,
    }


def set_dotted(table, key, value, origin):
    """table[a][b]...= value for key 'a.b...'; a number indexes a list."""
    parts = key.split(".")
    node = table
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        if isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                raise SweepError(f"sweep file '{origin}': '{key}': '{part}' is not an index of a list of {len(node)}")
            part = int(part)
        elif not isinstance(node, dict):
            raise SweepError(f"sweep file '{origin}': '{key}': '{parts[i - 1]}' holds a value, not a table")
        if last:
            node[part] = value
        else:
            if isinstance(node, dict) and part not in node:
                node[part] = {}
            node = node[part]


def trial_config(sweep, variant):
    """The config text of one variant: the base config with the variant's `set` keys applied."""
    import tomli_w

    base = tomllib.loads(sweep["config"].read_text())
    table = copy.deepcopy(base)
    if "extends" in table:
        # The trial's copy lives in another folder: the curriculum it builds on, found from there.
        table["extends"] = str((sweep["config"].parent / table["extends"]).resolve())
    # Each training uses the CPUs Ray gives its trial (unless the variant says otherwise).
    set_dotted(table, "runner.threads", sweep["cpus_per_trial"], sweep["origin"])
    for key, value in variant.get("set", {}).items():
        set_dotted(table, key, value, sweep["origin"])
    return tomli_w.dumps(table)


def find_flapper(explicit=None):
    """The flapper program: --flapper, $FLAPPER, `flapper` on PATH, or target/release/flapper above here."""
    for candidate in (explicit, os.environ.get("FLAPPER"), shutil.which("flapper")):
        if candidate and os.access(candidate, os.X_OK):
            return str(pathlib.Path(candidate).resolve())
    for folder in [pathlib.Path.cwd(), *pathlib.Path.cwd().parents]:
        built = folder / "target" / "release" / "flapper"
        if built.is_file():
            return str(built)
    raise SweepError("cannot find the flapper program: build it (cargo build --release -p flapper-cli), "
                     "put it on PATH (cargo install --path crates/flapper-cli) or pass --flapper PATH")


def training_command(flapper, command, run, config, seed):
    if command == "curriculum":
        return [flapper, "curriculum", "--out", str(run), "--config", str(config), "--seed", str(seed)]
    if (run / "checkpoints").is_dir():
        return [flapper, "train", "--resume", "--out", str(run)]
    return [flapper, "train", "--config", str(config), "--out", str(run), "--seed", str(seed)]


def progress(run):
    """The newest figures of a run folder: its last training row (of the latest stage) and validation."""
    stages = sorted(run.glob("stage*/training.csv")) or sorted(run.glob("training.csv"))
    metrics = {}
    if stages:
        rows = list(csv.DictReader(open(stages[-1])))
        if rows:
            last = rows[-1]
            metrics = {"stage": len(stages), "iteration": int(last["iteration"]), "env_steps": int(last["env_steps"]),
                       "mean_return": float(last["mean_return"])}
    selections = sorted(run.glob("stage*/selection.csv"))
    if selections:
        rows = list(csv.DictReader(open(selections[-1])))
        if rows:
            metrics["validation_completed_percent"] = float(rows[-1]["completed_percent"])
    return metrics


def run_trial(config):
    """A Ray Tune function trainable: one training run, its progress reported as it goes."""
    from ray import tune

    run = pathlib.Path(config["run"])
    command = training_command(config["flapper"], config["command"], run, config["config"], config["seed"])
    log = open(run.parent / "training.log", "a")
    process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT)
    last = None
    while True:
        finished = process.poll() is not None
        metrics = progress(run)
        if metrics and metrics != last:
            tune.report({k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in metrics.items()})
            last = metrics
        if finished:
            break
        time.sleep(config["poll_s"])
    if process.returncode != 0:
        tail = (run.parent / "training.log").read_text().strip().splitlines()[-1:]
        raise RuntimeError(f"{' '.join(command)} failed: {tail[0] if tail else process.returncode}")
    (run.parent / DONE).write_text(" ".join(command) + "\n")
    tune.report({**progress(run), "done": True})


def evaluate(flapper, trial, evaluation):
    """Flies the trial's controller on each evaluation reference; {name: (completed, rms_m)}."""
    policy = trial / "run" / "policy.safetensors"
    results = {}
    for name in evaluation.get("references", []):
        out = trial / "eval" / pathlib.Path(name).stem
        summary = out / "summary.csv"
        if not summary.exists():
            command = [flapper, "eval", "--policy", str(policy), "--reference", name, "--no-baseline", "--episodes",
                       str(evaluation.get("episodes", 100)), "--seed", str(evaluation.get("seed", 11)), "--out", str(out)]
            done = subprocess.run(command, capture_output=True, text=True)
            if done.returncode != 0:
                raise SweepError(f"{' '.join(command)}: {done.stderr.strip()}")
        rows = {row[0]: row[1] for row in csv.reader(open(summary))}
        completed = int(rows["completed"].split("/")[0])
        results[name] = (completed, float(rows["RMS position error (m), mean"]))
    return results


def totals(run):
    """(total environment steps, total wall time in s) of a finished run folder."""
    summary = run / "summary.json"
    if summary.exists():
        import json

        data = json.loads(summary.read_text())
        return data["total_env_steps"], data["total_wall_time_s"]
    rows = list(csv.DictReader(open(run / "training.csv")))
    return int(rows[-1]["env_steps"]), float(rows[-1]["wall_time_s"])


def write_results(out, trials, references):
    """results.csv (the columns of policies/final/seeds.csv, with `variant` first when there are several)."""
    several = len({t["variant"] for t in trials}) > 1
    header = (["variant"] if several else []) + ["seed", "total_env_steps", "total_wall_time_s"]
    for name in references:
        stem = pathlib.Path(name).stem
        header += [f"{stem}_completed", f"{stem}_rms_m"]
    with open(out / "results.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        for t in trials:
            row = ([t["variant"]] if several else []) + [t["seed"], t["steps"], f"{t['wall_s']:.1f}"]
            for name in references:
                completed, rms = t["evaluation"][name]
                row += [completed, f"{rms:.4f}"]
            writer.writerow(row)


def plot_results(out, trials, references):
    """results.png: each trial's learning curve (mean return against environment steps) and its completions."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2 if references else 1, figsize=(13 if references else 7, 4.5), squeeze=False)
    for t in trials:
        steps, returns, offset = [], [], 0
        files = sorted((t["dir"] / "run").glob("stage*/training.csv")) or [t["dir"] / "run" / "training.csv"]
        for path in files:
            rows = [r for r in csv.DictReader(open(path))]
            for r in rows:
                if r["mean_return"] not in ("nan", ""):
                    steps.append((offset + int(r["env_steps"])) / 1e6)
                    returns.append(float(r["mean_return"]))
            offset += int(rows[-1]["env_steps"]) if rows else 0
        axes[0][0].plot(steps, returns, label=t["name"], linewidth=0.8)
    axes[0][0].set(xlabel="environment steps (millions)", ylabel="mean episode return", title="learning curves")
    axes[0][0].legend(fontsize=8)
    if references:
        width = 0.8 / len(trials)
        for k, t in enumerate(trials):
            xs = [i + k * width for i in range(len(references))]
            axes[0][1].bar(xs, [t["evaluation"][n][0] for n in references], width, label=t["name"])
        axes[0][1].set_xticks([i + 0.4 - width / 2 for i in range(len(references))])
        axes[0][1].set_xticklabels([pathlib.Path(n).stem for n in references], rotation=30, ha="right", fontsize=8)
        axes[0][1].set(ylabel="episodes completed", title="evaluation")
    fig.tight_layout()
    fig.savefig(out / "results.png", dpi=110)
    plt.close(fig)


def run_sweep(sweep_path, out, address=None, flapper=None, poll_s=10.0, num_cpus=None):
    """Runs (or continues) the sweep into `out`; returns the trials' results."""
    sweep = load_sweep(sweep_path)
    flapper = find_flapper(flapper)
    out = pathlib.Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    trials = []
    for variant in sweep["variants"]:
        text = trial_config(sweep, variant)
        for seed in sweep["seeds"]:
            name = f"{variant['name']}-seed{seed}"
            folder = out / "trials" / name
            folder.mkdir(parents=True, exist_ok=True)
            config = folder / "config.toml"
            if config.exists() and config.read_text() != text:
                raise SweepError(f"'{folder}' was started with another config; use another --out or remove it")
            config.write_text(text)
            trials.append({"name": name, "variant": variant["name"], "seed": seed, "dir": folder, "config": config})
    pending = [t for t in trials if not (t["dir"] / DONE).exists()]
    print(f"sweep {sweep['origin'].name}: {len(trials)} trials, {len(trials) - len(pending)} finished already, "
          f"{len(pending)} to run ({sweep['cpus_per_trial']} CPUs each)", flush=True)
    if pending:
        import ray
        from ray import tune

        started_here = address is None
        ray.init(address=address, num_cpus=num_cpus if started_here else None, include_dashboard=False,
                 log_to_driver=False, ignore_reinit_error=True)
        try:
            space = {"trial": tune.grid_search([t["name"] for t in pending])}
            by_name = {t["name"]: t for t in pending}

            def trainable(params):
                t = by_name[params["trial"]]
                run_trial({"run": str(t["dir"] / "run"), "config": str(t["config"]), "seed": t["seed"],
                           "command": sweep["command"], "flapper": flapper, "poll_s": poll_s})

            tuner = tune.Tuner(
                tune.with_resources(trainable, {"cpu": sweep["cpus_per_trial"]}),
                param_space=space,
                run_config=tune.RunConfig(name="tune", storage_path=str(out / "ray"), verbose=1),
            )
            grid = tuner.fit()
            failed = [r.error for r in grid if r.error]
        finally:
            ray.shutdown()
        if failed:
            raise SweepError(f"{len(failed)} trial(s) failed; run the command again to continue them. First: {failed[0]}")
    evaluation = sweep["evaluation"] or {}
    references = evaluation.get("references", [])
    for t in trials:
        t["steps"], t["wall_s"] = totals(t["dir"] / "run")
        t["evaluation"] = evaluate(flapper, t["dir"], evaluation) if references else {}
    write_results(out, trials, references)
    plot_results(out, trials, references)
    print(f"wrote {out / 'results.csv'} and {out / 'results.png'}", flush=True)
    return trials


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m flapper.sweep", description=__doc__.splitlines()[0])
    parser.add_argument("sweep", help="the sweep file (TOML)")
    parser.add_argument("--out", required=True, help="sweep folder: trials/, results.csv, results.png")
    parser.add_argument("--address", help="join a running Ray cluster ('auto' finds it); default: a local Ray")
    parser.add_argument("--num-cpus", type=int, help="CPUs of the local Ray (default: all)")
    parser.add_argument("--flapper", help="the flapper program (default: $FLAPPER, PATH, target/release/flapper)")
    parser.add_argument("--poll-s", type=float, default=10.0, help="seconds between progress reports")
    args = parser.parse_args(argv)
    try:
        run_sweep(args.sweep, args.out, args.address, args.flapper, args.poll_s, args.num_cpus)
    except SweepError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
