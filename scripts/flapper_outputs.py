"""What flapper's measuring commands write, read back: the one place the scripts know these files.

`flapper sysid --out D` writes D/sysid.json (the identified fit per axis), `flapper modes --out D` writes
D/modes.json (the longitudinal reference's segments), `flapper frontier --out D` writes D/frontier.csv (its first
row the policy's point), judged against the efficient-bird bars it holds (`frontier_bars_met`). The scripts in this folder run such measurements on one
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


# The efficient-bird issue's bars that frontier.csv holds: energy on longitudinal at most 1.5 x the scripted
# gait's (bar 1), the glide segment at least half glided (2), the cruise flap fundamental within the paper's
# 4-6 Hz (3), level 3 m/s completed in at least 95% of its episodes at a mean RMS error of at most 0.5 m (5).
ENERGY_RATIO_BAR = 1.5
GLIDE_FRACTION_BAR = 0.5
CRUISE_FLAP_BAND_HZ = (4.0, 6.0)
LEVEL3_RMS_BAR_M = 0.5
LEVEL3_COMPLETED_SHARE = 0.95
EFFICIENCY_BARS = {"energy", "glide", "flap"}


def frontier_bars_met(energy_ratio, glide_fraction, cruise_flap_hz, level3=None):
    """The names of the bars a frontier point meets ("energy", "glide", "flap", "level3"); a figure that is None
    meets none. `level3`: (completed, episodes, mean RMS error in m) of the level 3 m/s path, or None."""
    met = set()
    if energy_ratio is not None and energy_ratio <= ENERGY_RATIO_BAR:
        met.add("energy")
    if glide_fraction is not None and glide_fraction >= GLIDE_FRACTION_BAR:
        met.add("glide")
    if cruise_flap_hz is not None and CRUISE_FLAP_BAND_HZ[0] <= cruise_flap_hz <= CRUISE_FLAP_BAND_HZ[1]:
        met.add("flap")
    if level3 is not None and level3_held(*level3[:2]) and level3[2] is not None and level3[2] <= LEVEL3_RMS_BAR_M:
        met.add("level3")
    return met


def level3_held(completed, episodes):
    """Whether the level 3 m/s path was completed in at least LEVEL3_COMPLETED_SHARE of its episodes."""
    return completed is not None and bool(episodes) and completed / episodes >= LEVEL3_COMPLETED_SHARE


def one_thread_env():
    """The environment for a flapper measurement on one thread (RAYON_NUM_THREADS=1)."""
    return {**os.environ, "RAYON_NUM_THREADS": "1"}
