#!/usr/bin/env python3
"""Do a training run's curves jump at checkpoint iterations? Reads training.csv files (flapper train) and
prints, after the first 100 iterations: the mean value loss and the mean number of finished episodes in the
three iterations after each checkpoint, each over its mean in all iterations (1.0 = no jump), and the largest
over the median of the value loss averaged by iteration modulo the checkpoint interval (1.0 = flat).
Usage: python3 scripts/checkpoint-periodicity.py RUN/training.csv [...] [--every 100]"""
import csv
import statistics
import sys


def main(argv):
    every = 100
    if "--every" in argv:
        i = argv.index("--every")
        every = int(argv[i + 1])
        del argv[i : i + 2]
    if not argv:
        sys.exit(__doc__)
    for path in argv:
        rows = [r for r in csv.DictReader(open(path)) if int(r["iteration"]) > every]
        if not rows:
            print(f"{path}: fewer than {every + 1} iterations")
            continue
        after = [r for r in rows if (int(r["iteration"]) - 1) % every < 3]

        def ratio(column):
            return statistics.mean(float(r[column]) for r in after) / statistics.mean(float(r[column]) for r in rows)

        by_phase = {}
        for r in rows:
            by_phase.setdefault((int(r["iteration"]) - 1) % every, []).append(float(r["value_loss"]))
        phase_means = [statistics.mean(v) for v in by_phase.values()]
        print(
            f"{path}: {len(rows)} iterations; after checkpoints / all: value loss {ratio('value_loss'):.2f}x, "
            f"episodes {ratio('episodes'):.2f}x; value loss by phase, max / median {max(phase_means) / statistics.median(phase_means):.2f}x"
        )


if __name__ == "__main__":
    main(sys.argv[1:])
