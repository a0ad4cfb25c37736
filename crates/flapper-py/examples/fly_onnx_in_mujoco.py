"""Fly an exported flapper policy (ONNX) in stock MuJoCo: the robot side of docs/deploy.md, step by step.

Needs only `numpy`, `mujoco` and `onnxruntime` (all in the .venv that `make python` builds); it does not
import flapper. Everything the robot must do around the policy is here, in the order docs/deploy.md
explains it: read the sensors into a frame (quaternion, body rates, joint positions, pitot airspeed, the
previous action), keep 25 frames of history, add the next 30 reference points in the body frame, run
the policy at 50 Hz, scale its actions to joint targets, low-pass them at 7 Hz and drive the PD servos
at 250 Hz. Every rate, size and range comes from the ONNX file's metadata.

    flapper reference longitudinal --out run/deploy/reference
    flapper export-policy --policy policies/final/policy.safetensors --format onnx --out run/deploy/policy.onnx
    flapper eval --policy policies/final/policy.safetensors --reference run/deploy/reference/reference.csv \\
        --episodes 1 --seed 11 --no-baseline --observations --out run/deploy/eval
    python crates/flapper-py/examples/fly_onnx_in_mujoco.py --onnx run/deploy/policy.onnx \\
        --reference run/deploy/reference/reference.csv --seconds 10 --eval run/deploy/eval/policy

With `--eval DIR` (what `flapper eval --observations` wrote for the policy) it starts from the same state
(DIR/start.json), compares its observations and actions with flapper's (DIR/observations.csv) step by
step, and prints flapper's RMS error over the same steps (DIR/steps.csv). `--replay` flies flapper's
recorded actions instead of the ONNX policy's: the observations must then equal flapper's to the bit at
every step (the sensors, the history, the body-frame path, the filter and the servo loop, without the
network).
"""

import argparse
import collections
import csv
import json
import math
import pathlib
import sys

import mujoco
import numpy as np
import onnxruntime

ROOT = pathlib.Path(__file__).resolve().parents[3]


# ----- the policy and what its file says ---------------------------------------------------------------


class OnnxPolicy:
    """The exported policy: `act(observation)` and the facts in its metadata."""

    def __init__(self, path):
        self.session = onnxruntime.InferenceSession(str(path), providers=["CPUExecutionProvider"])
        meta = self.session.get_modelmeta().custom_metadata_map
        self.observation_size = int(meta["observation_size"])
        self.history_frames = int(meta["history_frames"])
        self.frame_size = int(meta["frame_size"])
        self.lookahead_steps = int(meta["lookahead_steps"])
        self.observation_names = json.loads(meta["observation_names"])
        self.joint_names = json.loads(meta["joint_names"])
        self.half_range_rad = json.loads(meta["action_half_range_rad"])
        # Passive feathering (s): each wing's pitch target plus this times its own flap's rate; 0 for most policies.
        self.passive_feathering_s = float(meta.get("passive_feathering_s", 0.0))
        self.substeps = int(meta["substeps_per_control_step"])
        self.servo_rate_hz = float(meta["servo_rate_hz"])
        self.filter_cutoff_hz = float(meta["filter_cutoff_hz"])
        if meta["action_mode"] != "joint_targets":
            raise SystemExit(f"this example flies joint-target policies; the file's actions are {meta['action_mode']}")

    def act(self, observation):
        """Actions in [-1, 1] (float32) for one raw observation (float32)."""
        return self.session.run(["actions"], {"obs": observation[None, :]})[0][0]


# ----- geometry, as flapper computes it (glam's formulas, in float64) ---------------------------------


def rotate(q, v):
    """The vector v rotated by the unit quaternion q = (w, x, y, z): glam's DQuat * DVec3, term by term."""
    w, bx, by, bz = q
    b2 = (bx * bx + by * by) + bz * bz
    dot = (v[0] * bx + v[1] * by) + v[2] * bz
    cross = (by * v[2] - v[1] * bz, bz * v[0] - v[2] * bx, bx * v[1] - v[0] * by)
    s, t, u = w * w - b2, dot * 2.0, w * 2.0
    return tuple((v[i] * s + q[1 + i] * t) + cross[i] * u for i in range(3))


def to_body(q, v):
    """A world-frame vector in the body frame of q (the conjugate's rotation)."""
    return rotate((q[0], -q[1], -q[2], -q[3]), v)


def distance(a, b):
    d = [a[i] - b[i] for i in range(3)]
    return math.sqrt((d[0] * d[0] + d[1] * d[1]) + d[2] * d[2])


# ----- the reference ----------------------------------------------------------------------------------


def load_reference(path, dt_s):
    """A CSV of time_s, x_m, y_m, z_m resampled every dt_s by linear interpolation, as flapper reads it."""
    with open(path) as f:
        rows = [(float(r["time_s"]), (float(r["x_m"]), float(r["y_m"]), float(r["z_m"]))) for r in csv.DictReader(f)]
    t0, t1 = rows[0][0], rows[-1][0]
    points, segment = [], 0
    for k in range(int(math.floor((t1 - t0) / dt_s + 1e-9)) + 1):
        t = t0 + k * dt_s
        while segment + 2 < len(rows) and rows[segment + 1][0] < t:
            segment += 1
        (ta, pa), (tb, pb) = rows[segment], rows[min(segment + 1, len(rows) - 1)]
        u = min(max((t - ta) / (tb - ta), 0.0), 1.0) if tb > ta else 0.0
        points.append(tuple(pa[i] * (1.0 - u) + pb[i] * u for i in range(3)))
    return points


# ----- the robot: stock MuJoCo with flapper's MJCF -----------------------------------------------------


class Robot:
    """The MJCF in MuJoCo, with the 7 Hz filter in front of its PD servos (the robot's side of the policy)."""

    def __init__(self, model_path, policy):
        self.model = mujoco.MjModel.from_xml_path(str(model_path))
        self.data = mujoco.MjData(self.model)
        self.policy = policy
        m = self.model
        if abs(1.0 / m.opt.timestep - policy.servo_rate_hz) > 1e-6:
            raise SystemExit(f"the model steps at {1 / m.opt.timestep} Hz, the policy's servo loop at {policy.servo_rate_hz}")
        base = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "base")
        self.base_qpos, self.base_dof = m.jnt_qposadr[base], m.jnt_dofadr[base]
        joints = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name) for name in policy.joint_names]
        self.joint_qpos = [m.jnt_qposadr[j] for j in joints]
        self.joint_dof = [m.jnt_dofadr[j] for j in joints]
        self.actuators = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, name) for name in policy.joint_names]
        # First-order low-pass, exact for a target held over each 4 ms step: y += alpha (u - y).
        self.alpha = 1.0 - math.exp(-math.tau * policy.filter_cutoff_hz * m.opt.timestep)
        self.control_period_s = policy.substeps * m.opt.timestep

    def reset(self, start):
        """Puts the robot in `start` (position, orientation, velocities, joints); filter and servos hold the joints."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        d.qpos[self.base_qpos : self.base_qpos + 3] = start["position_m"]
        d.qpos[self.base_qpos + 3 : self.base_qpos + 7] = start["orientation_wxyz"]
        d.qvel[self.base_dof : self.base_dof + 3] = start["velocity_mps"]
        d.qvel[self.base_dof + 3 : self.base_dof + 6] = start["body_rates_radps"]
        for i in range(len(self.actuators)):
            d.qpos[self.joint_qpos[i]] = start["joint_positions_rad"][i]
            d.qvel[self.joint_dof[i]] = start["joint_velocities_radps"][i]
            d.ctrl[self.actuators[i]] = start["joint_positions_rad"][i]
        mujoco.mj_forward(m, d)
        self.filtered = list(start["joint_positions_rad"])

    def position(self):
        return tuple(self.data.qpos[self.base_qpos : self.base_qpos + 3])

    def orientation(self):
        return tuple(self.data.qpos[self.base_qpos + 3 : self.base_qpos + 7])

    def frame(self, previous_action):
        """One frame of sensor readings: quaternion w x y z, body rates p q r (rad/s), joint angles (rad),
        pitot airspeed (body-x velocity through the air, m/s), then the previous action."""
        d = self.data
        velocity = d.qvel[self.base_dof : self.base_dof + 3] - self.model.opt.wind
        airspeed = to_body(self.orientation(), tuple(velocity))[0]
        values = [*self.orientation(), *d.qvel[self.base_dof + 3 : self.base_dof + 6]]
        values += [d.qpos[a] for a in self.joint_qpos] + [airspeed]
        return np.array(values + list(previous_action), dtype=np.float64).astype(np.float32)

    def joint_velocities(self):
        return [self.data.qvel[a] for a in self.joint_dof]

    def apply(self, targets_rad):
        """One control period: the joint targets through the filter into the PD servos, one MuJoCo step each."""
        for _ in range(self.policy.substeps):
            self.filtered = [y + self.alpha * (u - y) for y, u in zip(self.filtered, targets_rad)]
            for actuator, target in zip(self.actuators, self.filtered):
                self.data.ctrl[actuator] = target
            mujoco.mj_step(self.model, self.data)


def nominal_start(reference, dt_s, joints):
    """Without flapper's start: at the path's first point, flying along it at its speed, nose 20 deg up."""
    a, b = reference[0], reference[1]
    heading = math.atan2(b[1] - a[1], b[0] - a[0])
    speed = distance(a, b) / dt_s
    half_yaw, half_pitch = heading / 2, -math.radians(20.0) / 2
    cy, sy, cp, sp = math.cos(half_yaw), math.sin(half_yaw), math.cos(half_pitch), math.sin(half_pitch)
    return {
        "position_m": list(a),
        "orientation_wxyz": [cy * cp, -sy * sp, cy * sp, sy * cp],
        "velocity_mps": [speed * math.cos(heading), speed * math.sin(heading), 0.0],
        "body_rates_radps": [0.0] * 3,
        "joint_positions_rad": [0.0] * joints,
        "joint_velocities_radps": [0.0] * joints,
    }


# ----- the control loop ---------------------------------------------------------------------------------


def fly(policy, robot, reference, start, steps, recorded_actions=None):
    """Flies up to `steps` control steps; returns the observations, the actions and the position errors.
    With `recorded_actions`, flies those instead of the policy's."""
    lookahead, max_error_m = policy.lookahead_steps, 3.0
    robot.reset(start)
    target = lambda k: reference[min(k, len(reference) - 1)]  # noqa: E731
    # The previous action at rest: the joint-target action that holds the joints where they are.
    previous = [np.float32(min(max(start["joint_positions_rad"][i] / h, -1.0), 1.0)) for i, h in enumerate(policy.half_range_rad)]
    history = collections.deque([robot.frame(previous)] * policy.history_frames, maxlen=policy.history_frames)
    observations, actions, errors = [], [], []
    for step in range(steps):
        position, orientation = robot.position(), robot.orientation()
        ahead = [to_body(orientation, tuple(target(step + 1 + i)[j] - position[j] for j in range(3))) for i in range(lookahead)]
        observation = np.concatenate([*history, np.array(ahead, dtype=np.float64).astype(np.float32).ravel()])
        action = policy.act(observation) if recorded_actions is None else recorded_actions[step]
        observations.append(observation)
        actions.append(action)
        # Actions -> joint targets (rad): clipped to [-1, 1], a non-finite one counts as 0.
        clipped = [min(max(float(a), -1.0), 1.0) if math.isfinite(a) else 0.0 for a in action]
        targets = [a * h for a, h in zip(clipped, policy.half_range_rad)]
        if policy.passive_feathering_s > 0.0:
            # Each wing's pitch (q2, q4) twists with its own flap's rate (q1, q3) as read this step.
            rates = robot.joint_velocities()
            for flap, pitch in ((0, 1), (2, 3)):
                h = policy.half_range_rad[pitch]
                targets[pitch] = min(max(targets[pitch] + policy.passive_feathering_s * rates[flap], -h), h)
        robot.apply(targets)
        previous = [np.float32(min(max(t / h, -1.0), 1.0)) for t, h in zip(targets, policy.half_range_rad)]
        errors.append(distance(target(step + 1), robot.position()))
        if errors[-1] > max_error_m or step + 2 >= len(reference) - lookahead:
            break
        history.append(robot.frame(previous))
    return np.array(observations), np.array(actions, dtype=np.float32), errors


def rms(errors):
    total = 0.0
    for e in errors:
        total += e * e
    return math.sqrt(total / len(errors))


def read_eval(folder, observation_size):
    """flapper eval's episode 0: its start, observations and actions, and its position errors."""
    folder = pathlib.Path(folder)
    start = json.loads((folder / "start.json").read_text())
    with open(folder / "observations.csv") as f:
        rows = list(csv.reader(f))[1:]
    recorded = np.array([[np.float32(v) for v in row[1:]] for row in rows], dtype=np.float32)
    with open(folder / "steps.csv") as f:
        errors = [float(r["error_m"]) for r in csv.DictReader(f) if r["episode"] == "0"]
    return start, recorded[:, :observation_size], recorded[:, observation_size:], errors


def compare(policy, period_s, observations, actions, eval_observations, eval_actions):
    """Step by step: where the observations and actions first differ from flapper's, and by how much."""
    n = min(len(observations), len(eval_observations))
    same = [np.array_equal(observations[k].view(np.uint32), eval_observations[k].view(np.uint32)) for k in range(n)]
    first = next((k for k in range(n) if not same[k]), None)
    if first is None:
        print(f"observations: identical to flapper eval's, bit for bit, at all {n} steps")
    else:
        index = int(np.argmax(np.abs(observations[first] - eval_observations[first])))
        print(f"observations: identical to flapper eval's for {first} steps; step {first} differs first "
              f"(largest at {policy.observation_names[index]}: {observations[first][index]!r} against "
              f"{eval_observations[first][index]!r})")
    action_difference = np.abs(np.clip(actions[:n], -1, 1) - np.clip(eval_actions[:n], -1, 1)).max(axis=1)
    observation_difference = np.abs(observations[:n] - eval_observations[:n]).max(axis=1)
    marks = [k for k in (0, 1, 10, 50, 100, 200, 300, 400, 499) if k < n]
    for k in marks:
        print(f"  step {k:3d} ({k * period_s:5.2f} s): max |action - flapper's| {action_difference[k]:.2e}, "
              f"max |observation - flapper's| {observation_difference[k]:.2e}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--onnx", required=True, help="the policy (flapper export-policy --format onnx)")
    parser.add_argument("--reference", required=True, help="a reference CSV (time_s,x_m,y_m,z_m), e.g. flapper reference's")
    parser.add_argument("--model", default=str(ROOT / "models/flapper.xml"), help="the robot's MJCF")
    parser.add_argument("--seconds", type=float, default=10.0, help="how long to fly at most (default 10)")
    parser.add_argument("--eval", metavar="DIR", help="what `flapper eval --observations` wrote for the policy")
    parser.add_argument("--replay", action="store_true", help="fly flapper eval's recorded actions (needs --eval)")
    args = parser.parse_args(argv)
    if args.replay and not args.eval:
        parser.error("--replay needs --eval DIR")

    policy = OnnxPolicy(args.onnx)
    robot = Robot(args.model, policy)
    reference = load_reference(args.reference, robot.control_period_s)
    steps = int(round(args.seconds / robot.control_period_s))
    if args.eval:
        start, eval_observations, eval_actions, eval_errors = read_eval(args.eval, policy.observation_size)
    else:
        start = nominal_start(reference, robot.control_period_s, len(policy.joint_names))
    recorded = eval_actions if args.replay else None
    if recorded is not None:
        steps = min(steps, len(recorded))
    observations, actions, errors = fly(policy, robot, reference, start, steps, recorded)
    flown = len(errors)
    who = "flapper eval's recorded actions" if args.replay else "the ONNX policy (onnxruntime)"
    print(f"{who} in stock MuJoCo {mujoco.__version__}: {flown} steps ({flown * robot.control_period_s:.2f} s), "
          f"RMS position error {rms(errors):.4f} m, max {max(errors):.3f} m")
    if args.eval:
        same = eval_errors[:flown]
        print(f"flapper eval on the same start, the same {len(same)} steps: RMS position error {rms(same):.4f} m, "
              f"max {max(same):.3f} m (whole episode: {len(eval_errors)} steps, RMS {rms(eval_errors):.4f} m)")
        compare(policy, robot.control_period_s, observations, actions, eval_observations, eval_actions)
    return 0


if __name__ == "__main__":
    sys.exit(main())
