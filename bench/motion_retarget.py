"""FK + retarget of a 60-frame clip onto the ~100-bone anny skeleton: microseconds per frame.

Source: an AMASS-style SMPL-X motion (55 joints) and a procedural walk (27 joints). Prints JSON.
"""
from __future__ import annotations

import json
import time

import numpy as np


def timed(fn, repeat: int = 5) -> float:
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def main() -> dict:
    import synmitsuba as sm
    from synmitsuba.body.anny_model import anny_body
    from synmitsuba.geometry import axis_angle_to_matrix
    target = anny_body().skeleton
    rng = np.random.default_rng(0)
    walk = sm.procedural_motion("walk", rng, seconds=2.0)
    smplx = sm.smplx_skeleton()
    F = 60
    amass = sm.Motion(smplx, axis_angle_to_matrix(rng.normal(0, 0.2, (F, len(smplx), 3))),
                      np.zeros((F, 3)), 30.0)
    out = {"bench": "motion_retarget", "frames": F, "target_bones": len(target), "runs": []}
    for name, motion in (("procedural_walk", walk), ("smplx_random", amass)):
        fk = timed(lambda: motion.joint_positions())
        rt = timed(lambda: sm.retarget(motion, target))
        out["runs"].append({"source": name, "source_joints": len(motion.skeleton),
                            "fk_us_per_frame": round(1e6 * fk / F, 2),
                            "retarget_us_per_frame": round(1e6 * rt / F, 2)})
    return out


if __name__ == "__main__":
    print(json.dumps(main(), indent=1))
