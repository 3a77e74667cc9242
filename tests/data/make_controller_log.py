"""Writes controller_log.csv: a synthetic 100 Hz log of a motion controller driving the
reference platform, as a real controller writes it.

* ``Timestamp [us]``: a uint32 microsecond counter that wraps around 2**32 after 7.5 s;
  the time stamps jitter by up to 0.3 % of the 10 ms step (the poses are sampled at them);
* ``Surge/Sway/Heave [mm]``: the position in the controller's frame: x forward, y to the
  right, z down, and zero at the home pose 0.75 m above the base joints (so
  ``axes = ["x", "-y", "-z"]`` and ``offset.z = 0.75`` map it onto the platform's frame);
* ``Roll/Pitch/Yaw [deg]``: the orientation in that frame (extrinsic x, y, z);
* ``Surge/Sway/Heave vel [mm/s]``: the controller's own velocity, in its frame;
* ``Act1..Act6 [N]``: the load cells, with a hidden seal friction of 20 N and 0.5 N of noise;
* ``Mode``: the controller's state (not a gsfric input);
* a last row of zeros, written as the controller stops.

Run ``python tests/data/make_controller_log.py`` to write it again (the same seed gives the
same file).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from gsfric.models import reference_platform
from gsfric.signal.rotations import rotation_from_quaternion, rpy_from_rotation
from gsfric.synth import excitation_motion, synthesize

HERE = Path(__file__).resolve().parent
ROWS, RATE, JITTER = 2000, 100.0, 0.003
HOME = 0.75
FLIP = np.diag([1.0, -1.0, -1.0])          # the controller's axes in the platform's frame


def controller_log(seed: int = 35) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    step = 1.0 / RATE
    t = np.arange(ROWS) * step + rng.uniform(-0.5, 0.5, ROWS) * JITTER * step
    t -= t[0]
    motion = excitation_motion(rng, t, scale=0.8)
    data = synthesize(reference_platform(), ["seal_friction:force=20"], motion=motion,
                      noise=0.5, pose_noise=2e-5, seed=seed)
    frame = data.frame
    position = frame[["x", "y", "z"]].to_numpy()
    log_position = (position - [0.0, 0.0, HOME]) @ FLIP        # FLIP is its own inverse
    rotation = rotation_from_quaternion(frame[["qw", "qx", "qy", "qz"]].to_numpy())
    log_rotation = FLIP @ rotation @ FLIP
    velocity = motion.velocity @ FLIP
    counts = (2**32 - 7_500_000 + np.round(t * 1e6).astype(np.int64)) % 2**32
    log = pd.DataFrame({"Timestamp [us]": counts.astype(np.uint32)})
    for k, name in enumerate(("Surge", "Sway", "Heave")):
        log[f"{name} [mm]"] = np.round(log_position[:, k] * 1e3, 4)
    for k, name in enumerate(("Roll", "Pitch", "Yaw")):
        log[f"{name} [deg]"] = np.round(np.degrees(rpy_from_rotation(log_rotation)[:, k]), 5)
    for k, name in enumerate(("Surge", "Sway", "Heave")):
        log[f"{name} vel [mm/s]"] = np.round(velocity[:, k] * 1e3, 3)
    for i in range(1, 7):
        log[f"Act{i} [N]"] = np.round(frame[f"F{i}"].to_numpy(), 3)
    log["Mode"] = 3
    stop = pd.DataFrame({name: [0] for name in log.columns}).astype(log.dtypes.to_dict())
    return pd.concat([log, stop], ignore_index=True)


if __name__ == "__main__":
    controller_log().to_csv(HERE / "controller_log.csv", index=False)
