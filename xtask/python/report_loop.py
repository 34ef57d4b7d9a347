"""The report's control program (its section 6.6), headless, with the official MuJoCo Python
bindings, for `cargo xtask bench`'s side-by-side comparison with `sim-host run`.

Same model and schedule as the Rust run it is compared with: the project's model, one control
step per MuJoCo step (0.004 s), STOP for 1 s and then the report's trot (`L`: its joint-space
sinusoids through `smooth_set`). As the report does it: every step logs the wheel torques and
the front-left leg's joints, looking the joints up by name, and the trot builds its phase table;
after the loop the two figures are drawn (saved as PNG: there is no screen). Only the viewer and
the wall-clock pacing are left out: as fast as it goes.

`--hoisted` is the same program with the joints' lookups by name taken out of the loop, the
rest as written.

usage: report_loop.py MODEL.xml SECONDS OUT_DIR [--hoisted]
prints JSON: {"steps": N, "loop_s": T, "steps_per_s": N / T}
"""

import json
import os
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402


def main(model_path, seconds, out_dir, hoisted):
    model = mujoco.MjModel.from_xml_path(model_path)
    data = mujoco.MjData(model)

    def get_act(name):
        return model.actuator(name).id

    wheel_l = get_act("m_wheel_left")
    wheel_r = get_act("m_wheel_right")
    legs = {
        side: [get_act(f"m_{joint}_{side}") for joint in ("hip1", "hip2", "knee", "ankle")]
        for side in ("fl", "fr", "bl", "br")
    }
    omega = 2 * np.pi * 1.0
    hip_amp, knee_base, knee_amp, ank_amp = 0.35, -0.7, 0.25, 0.15

    def smooth_set(current, target, rate=8.0):
        return current + rate * (target - current) * model.opt.timestep

    def gait(t, phase):
        hip2 = hip_amp * np.sin(omega * t + phase)
        knee = knee_base + knee_amp * np.sin(omega * t + phase)
        ank = ank_amp * np.sin(omega * t + phase)
        return [0, hip2, knee, ank]

    def leg_forward(t):
        data.ctrl[wheel_l] = 0
        data.ctrl[wheel_r] = 0
        phases = {"fl": 0, "br": 0, "fr": np.pi, "bl": np.pi}
        for side in legs:
            desired = gait(t, phases[side])
            for i, act in enumerate(legs[side]):
                data.ctrl[act] = smooth_set(data.ctrl[act], desired[i])

    def stop_all():
        for i in range(model.nu):
            data.ctrl[i] = 0

    hip2 = model.joint("hip2_fl").qposadr
    knee = model.joint("knee_fl").qposadr
    ankle = model.joint("ankle_fl").qposadr
    times, torque_l, torque_r, hip_log, knee_log, ankle_log = [], [], [], [], [], []
    dt = model.opt.timestep
    steps = int(round(seconds / dt))
    start = time.perf_counter()
    for k in range(steps):
        t = k * dt
        times.append(t)
        torque_l.append(data.actuator_force[wheel_l])
        torque_r.append(data.actuator_force[wheel_r])
        if hoisted:
            hip_log.append(data.qpos[hip2])
            knee_log.append(data.qpos[knee])
            ankle_log.append(data.qpos[ankle])
        else:
            hip_log.append(data.qpos[model.joint("hip2_fl").qposadr])
            knee_log.append(data.qpos[model.joint("knee_fl").qposadr])
            ankle_log.append(data.qpos[model.joint("ankle_fl").qposadr])
        if t < 1.0:
            stop_all()
        else:
            leg_forward(t)
        mujoco.mj_step(model, data)
    loop_s = time.perf_counter() - start
    draw(out_dir, times, torque_l, torque_r, hip_log, knee_log, ankle_log)
    json.dump({"steps": steps, "loop_s": loop_s, "steps_per_s": steps / loop_s}, sys.stdout)


def draw(out_dir, times, torque_l, torque_r, hip_log, knee_log, ankle_log):
    """The report's two figures, saved instead of shown."""
    os.makedirs(out_dir, exist_ok=True)
    plt.figure(figsize=(10, 5))
    plt.plot(times, torque_l, label="Left Wheel Torque")
    plt.plot(times, torque_r, label="Right Wheel Torque")
    plt.xlabel("Time [s]")
    plt.ylabel("Torque [N·m]")
    plt.title("Wheel Torque vs Time")
    plt.legend()
    plt.grid(True)
    plt.savefig(os.path.join(out_dir, "wheel_torque.png"))
    plt.figure(figsize=(10, 5))
    plt.plot(times, np.ravel(hip_log), label="Hip Joint (FL)")
    plt.plot(times, np.ravel(knee_log), label="Knee Joint (FL)")
    plt.plot(times, np.ravel(ankle_log), label="Ankle Joint (FL)")
    plt.xlabel("Time [s]")
    plt.ylabel("Joint Angle [rad]")
    plt.title("Front-Left Leg Joint Angles vs Time")
    plt.legend()
    plt.grid(True)
    plt.savefig(os.path.join(out_dir, "leg_joints.png"))


if __name__ == "__main__":
    if len(sys.argv) not in (4, 5) or sys.argv[4:] not in ([], ["--hoisted"]):
        sys.exit("usage: report_loop.py MODEL.xml SECONDS OUT_DIR [--hoisted]")
    main(sys.argv[1], float(sys.argv[2]), sys.argv[3], sys.argv[4:] == ["--hoisted"])
