#!/usr/bin/env python3
"""Writes the example paths that no training stage draws (examples/*.csv, `time_s,x_m,y_m,z_m` at 10 Hz, from
(0, 0, 10) m heading along x): a climbing helix, a descending spiral, a figure of eight and a zig-zag, each at
4 m/s. `flapper eval --reference examples/NAME.csv` flies them like any path (README, "Fly your own path").

    python3 scripts/example-paths.py [--out examples]

The older examples (level-*.csv, s-turn.csv, longitudinal-tailwind-1mps.csv) are left as they are.
"""

import argparse
import math
import pathlib

STEP_S = 0.1
START_Z_M = 10.0
SPEED_MPS = 4.0


def circle_arc(radius_m, duration_s, climb_mps, side):
    """A circle of `radius_m` flown at SPEED_MPS from the origin heading along x, turning left (`side` = 1) or
    right (-1), rising at `climb_mps`."""
    points = []
    for i in range(round(duration_s / STEP_S) + 1):
        t = i * STEP_S
        angle = SPEED_MPS * t / radius_m
        points.append((t, radius_m * math.sin(angle), side * radius_m * (1.0 - math.cos(angle)), START_Z_M + climb_mps * t))
    return points


def figure_eight(radius_m):
    """Two circles of `radius_m` touching at the origin, one lap each at SPEED_MPS: the left one, then the
    right one."""
    lap_m = 2.0 * math.pi * radius_m
    points = []
    for i in range(round(2.0 * lap_m / SPEED_MPS / STEP_S) + 1):
        t = i * STEP_S
        flown_m = SPEED_MPS * t
        side = 1.0 if flown_m < lap_m else -1.0
        angle = (flown_m if flown_m < lap_m else flown_m - lap_m) / radius_m
        points.append((t, radius_m * math.sin(angle), side * radius_m * (1.0 - math.cos(angle)), START_Z_M))
    return points


def zigzag(duration_s, heading_deg, leg_s, settle_s):
    """Straight legs of `leg_s` at +-`heading_deg` off x, the heading eased to each new side with a time
    constant of `settle_s`."""
    points, x, y, heading = [], 0.0, 0.0, 0.0
    for i in range(round(duration_s / STEP_S) + 1):
        t = i * STEP_S
        points.append((t, x, y, START_Z_M))
        side = 1.0 if int(t / leg_s) % 2 == 0 else -1.0
        heading += (side * math.radians(heading_deg) - heading) * min(1.0, STEP_S / settle_s)
        x += SPEED_MPS * math.cos(heading) * STEP_S
        y += SPEED_MPS * math.sin(heading) * STEP_S
    return points


PATHS = {
    "helix-climb": lambda: circle_arc(8.0, 20.0, 0.4, 1),
    "spiral-descent": lambda: circle_arc(8.0, 20.0, -0.5, -1),
    "figure-eight": lambda: figure_eight(7.0),
    "zigzag": lambda: zigzag(20.0, 30.0, 3.0, 0.6),
}


def write(path, points):
    with open(path, "w") as f:
        f.write("time_s,x_m,y_m,z_m\n")
        for t, x, y, z in points:
            f.write(f"{t:.1f},{x:.4f},{y:.4f},{z:.4f}\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="examples", help="folder to write the CSV files into (default: examples)")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    if not out.is_dir():
        parser.error(f"--out {out}: no such folder")
    for name, make in PATHS.items():
        write(out / f"{name}.csv", make())
        print(f"wrote {out / name}.csv")


if __name__ == "__main__":
    main()
