"""What flapper's measuring commands write, read back: the one place the scripts know these files.

`flapper sysid --out D` writes D/sysid.json (the identified fit per axis), `flapper modes --out D` writes
D/modes.json (the longitudinal reference's segments), `flapper frontier --out D` writes D/frontier.csv (its first
row the policy's point). The scripts in this folder run such measurements on one
thread each, side by side (`one_thread_env`); flapper's bits do not depend on the thread count.
"""

import csv
import json
import os


def identified_fits(folder):
    """The identified closed loop's validation fit (%) per axis, {"x": .., "y": .., "z": ..}, from the
    sysid.json `flapper sysid --out FOLDER` wrote."""
    with open(folder / "sysid.json") as f:
        result = json.load(f)
    return {axis: result[axis]["fit_percent"] for axis in "xyz"}


def modes_segments(folder):
    """The longitudinal reference's segments (cruise, climb, glide, dive) keyed by name, each the dict of
    figures (glide_fraction, flap_fundamental_hz, ...) from the modes.json `flapper modes --out FOLDER` wrote."""
    with open(folder / "modes.json") as f:
        return {segment["segment"]: segment for segment in json.load(f)["segments"]}


def frontier_point(folder):
    """The first row of the frontier.csv `flapper frontier --out FOLDER` wrote (the policy's point; the
    scripted gait's comes after it), as strings keyed by column."""
    with open(folder / "frontier.csv", newline="") as f:
        return next(csv.DictReader(f))


def one_thread_env():
    """The environment for a flapper measurement on one thread (RAYON_NUM_THREADS=1)."""
    return {**os.environ, "RAYON_NUM_THREADS": "1"}
