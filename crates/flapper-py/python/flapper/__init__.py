"""flapper from Python: the flapping-wing robot's trajectory-tracking task as a Gymnasium vector
environment (stepped by flapper's Rust code on its own threads) and flapper's trained policies.

    import flapper
    env = flapper.FlightVectorEnv(256, stage=1, seed=0)
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
"""

import ctypes
import importlib.util
import os


def _load_mujoco_library():
    # flapper's extension links against libmujoco.so.3.17.0; the `mujoco` wheel (a dependency)
    # carries it. Loading it first, globally, lets the extension find it by its soname.
    spec = importlib.util.find_spec("mujoco")
    if spec is None or not spec.submodule_search_locations:
        raise ImportError("flapper needs the `mujoco==3.17.0` package: pip install mujoco==3.17.0")
    for folder in spec.submodule_search_locations:
        path = os.path.join(folder, "libmujoco.so.3.17.0")
        if os.path.exists(path):
            ctypes.CDLL(path, mode=ctypes.RTLD_GLOBAL)
            return
    raise ImportError("the installed `mujoco` package has no libmujoco.so.3.17.0: pip install mujoco==3.17.0")


_load_mujoco_library()

from ._flapper import Policy, named_reference_start_m, reference_names  # noqa: E402
from .vector_env import FlightVectorEnv  # noqa: E402

__all__ = ["FlightVectorEnv", "Policy", "reference_names", "named_reference_start_m"]
