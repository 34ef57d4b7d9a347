"""The report's control loop (its section 6.6), re-implemented headless with the official MuJoCo
Python bindings, for `cargo xtask bench`'s side-by-side comparison with `sim-host run`.

Same model and schedule as the Rust run it is compared with: the project's model, one control
step per MuJoCo step (0.004 s), STOP for 1 s and then the report's trot (`L`: its joint-space
sinusoids through `smooth_set`), and the report's logging (wheel torques and the front-left
leg's joints appended every step). No viewer and no sleeping: as fast as it goes.

usage: report_loop.py MODEL.xml SECONDS
prints JSON: {"steps": N, "loop_s": T, "steps_per_s": N / T}
"""

import json
import sys
import time

import mujoco
import numpy as np


def main(model_path, seconds):
    model = mujoco.MjModel.from_xml_path(model_path)
    data = mujoco.MjData(model)

    def act(name):
        return model.actuator(name).id

    legs = {
        side: [act(f"m_{joint}_{side}") for joint in ("hip1", "hip2", "knee", "ankle")]
        for side in ("fl", "fr", "bl", "br")
    }
    wheel_l, wheel_r = act("m_wheel_left"), act("m_wheel_right")
    omega = 2 * np.pi * 1.0
    hip_amp, knee_base, knee_amp, ank_amp = 0.35, -0.7, 0.25, 0.15
    phases = {"fl": 0, "br": 0, "fr": np.pi, "bl": np.pi}
    dt = model.opt.timestep

    def smooth_set(current, target, rate=8.0):
        return current + rate * (target - current) * dt

    def gait(t, phase):
        s = np.sin(omega * t + phase)
        return [0, hip_amp * s, knee_base + knee_amp * s, ank_amp * s]

    hip2 = model.joint("hip2_fl").qposadr
    knee = model.joint("knee_fl").qposadr
    ankle = model.joint("ankle_fl").qposadr
    times, torque_l, torque_r, hip_log, knee_log, ankle_log = [], [], [], [], [], []
    steps = int(round(seconds / dt))
    start = time.perf_counter()
    for k in range(steps):
        t = k * dt
        times.append(t)
        torque_l.append(data.actuator_force[wheel_l])
        torque_r.append(data.actuator_force[wheel_r])
        hip_log.append(data.qpos[hip2])
        knee_log.append(data.qpos[knee])
        ankle_log.append(data.qpos[ankle])
        if t < 1.0:
            for i in range(model.nu):
                data.ctrl[i] = 0
        else:
            data.ctrl[wheel_l] = 0
            data.ctrl[wheel_r] = 0
            for side, acts in legs.items():
                desired = gait(t, phases[side])
                for i, a in enumerate(acts):
                    data.ctrl[a] = smooth_set(data.ctrl[a], desired[i])
        mujoco.mj_step(model, data)
    loop_s = time.perf_counter() - start
    json.dump({"steps": steps, "loop_s": loop_s, "steps_per_s": steps / loop_s}, sys.stdout)


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]))
