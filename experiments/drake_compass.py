#!/usr/bin/env python3
"""Compass gait with Drake (pydrake.examples.CompassGait, default parameters): steady-state gait,
stride period, post-impact state, and Floquet multipliers by central finite differences of
Drake's own stride map. Writes experiments/results/drake_compass/drake.json, which the Rust
binary `drake_compass` puts side by side with pdw-sweep's numbers.

Drake's coordinates: `stance`, `swing` are absolute leg angles from the world vertical, the
continuous state is (stance, swing, stancedot, swingdot); heel strike is the witness
`slope - (stance + swing)/2` crossing zero, then Drake's own impact map and leg swap.
pdw-sweep's compass section is (q1, q1dot, q2dot) with q1 the stance-leg angle from the slope
normal (positive with the stance foot downhill of the hip) and q2 the swing leg relative to the
stance leg, so
    q1 = slope - stance,  q1dot = -stancedot,  q2dot = stancedot - swingdot,
and on the section swing = 2 slope - stance.

Stride map: the simulator starts from a post-impact state and runs until Drake applies the next
impact (its "left support" flag flips). The monitor sees the pre-impact state at the isolated
event time t_e, then the state at the end of the first step after the reset (t_m > t_e); the
post-impact state at t_e is recovered by integrating Drake's own vector field
(CalcTimeDerivatives) backward from t_m to t_e with 400 classical RK4 steps (error < 1e-15 for a
step of at most 0.05 s).

Usage: python3 experiments/drake_compass.py [accuracy ...]   (default 1e-6 1e-8 1e-10 1e-12)
"""
import json
import os
import sys
import time

import numpy as np
from pydrake.examples import CompassGait, CompassGaitParams
from pydrake.systems.analysis import ResetIntegratorFromFlags, Simulator
from pydrake.systems.framework import EventStatus

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results", "drake_compass")


class DrakeStrideMap:
    """P: pdw section (q1, q1dot, q2dot) -> next post-impact section state, by Drake."""

    def __init__(self, accuracy, integrator="runge_kutta5", max_step=0.05):
        self.plant = CompassGait()
        self.sim = Simulator(self.plant)
        ResetIntegratorFromFlags(self.sim, integrator, max_step)
        self.ctx = self.sim.get_mutable_context()
        self.ctx.SetAccuracy(accuracy)
        self.sim.get_mutable_integrator().set_target_accuracy(accuracy)
        p = self.plant.get_parameters(self.ctx) if hasattr(self.plant, "get_parameters") else CompassGaitParams()
        self.params = p
        self.slope = p.slope()
        self.deriv_ctx = self.plant.CreateDefaultContext()
        self.deriv = self.plant.AllocateTimeDerivatives()
        self.sim.set_monitor(self._monitor)

    def f(self, x):
        self.deriv_ctx.get_mutable_continuous_state_vector().SetFromVector(x)
        self.plant.CalcTimeDerivatives(self.deriv_ctx, self.deriv)
        return self.deriv.CopyToVector()

    def back(self, x, dt, n=400):
        """Integrate Drake's vector field from x backward by dt (RK4, n steps)."""
        h = -dt / n
        for _ in range(n):
            k1 = self.f(x)
            k2 = self.f(x + 0.5 * h * k1)
            k3 = self.f(x + 0.5 * h * k2)
            k4 = self.f(x + h * k3)
            x = x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        return x

    def _monitor(self, c):
        x = c.get_continuous_state_vector().CopyToVector().copy()
        flag = c.get_abstract_state(0).get_value()
        if flag != self.flag0:
            self.result = (self.last[0], self.last[1], c.get_time(), x)
            return EventStatus.ReachedTermination(self.plant, "impact applied")
        self.last = (c.get_time(), x)
        return EventStatus.Succeeded()

    def to_drake(self, s):
        stance = self.slope - s[0]
        return np.array([stance, 2 * self.slope - stance, -s[1], -s[1] - s[2]])

    def to_section(self, x):
        return np.array([self.slope - x[0], -x[2], x[2] - x[3]])

    def stride(self, s):
        """(next section state, stride period, pre-impact Drake state)."""
        self.ctx.SetTime(0.0)
        self.ctx.get_mutable_continuous_state_vector().SetFromVector(self.to_drake(s))
        self.flag0 = self.ctx.get_abstract_state(0).get_value()
        self.result = None
        self.last = (0.0, self.to_drake(s))
        self.sim.Initialize()
        self.sim.AdvanceTo(5.0)
        if self.result is None:
            raise RuntimeError("no heel strike within 5 s")
        t_e, x_pre, t_m, x_m = self.result
        x_post = self.back(x_m, t_m - t_e)
        return self.to_section(x_post), t_e, x_pre


def fd_jacobian(P, s, h):
    n = len(s)
    J = np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        J[:, j] = (P(s + e) - P(s - e)) / (2 * h)
    return J


def run(accuracy, guess):
    m = DrakeStrideMap(accuracy)
    P = lambda s: m.stride(s)[0]
    # Steady state by simulation (strides from the guess), then Newton on Drake's map.
    s = np.array(guess, dtype=float)
    hist = []
    t0 = time.perf_counter()
    n_sim = 60
    for _ in range(n_sim):
        s_next = P(s)
        hist.append(float(np.max(np.abs(s_next - s))))
        s = s_next
    t_stride = (time.perf_counter() - t0) / n_sim
    s_sim = s.copy()
    h_fd = max(1e-6, 10 * accuracy ** 0.5)
    newton = []
    for _ in range(6):
        r = P(s) - s
        newton.append(float(np.max(np.abs(r))))
        J = fd_jacobian(P, s, h_fd) - np.eye(3)
        s = s - np.linalg.solve(J, r)
    r = P(s) - s
    newton.append(float(np.max(np.abs(r))))
    _, period, x_pre = m.stride(s)
    mults = {}
    for h in [1e-3, 1e-4, 1e-5, 1e-6]:
        lam = np.linalg.eigvals(fd_jacobian(P, s, h))
        lam = sorted(lam, key=lambda z: -abs(z))
        mults[f"{h:.0e}"] = [[float(z.real), float(z.imag)] for z in lam]
    # Plain simulation speed: a fresh simulator without monitor (no Python in the loop),
    # 200 strides from the fixed point.
    plain = DrakeStrideMap(accuracy)
    plain.sim.clear_monitor()
    plain.ctx.SetTime(0.0)
    plain.ctx.get_mutable_continuous_state_vector().SetFromVector(plain.to_drake(s))
    plain.sim.Initialize()
    t0 = time.perf_counter()
    plain.sim.AdvanceTo(200 * period)
    t_plain = (time.perf_counter() - t0) / 200
    x_end = plain.ctx.get_continuous_state_vector().CopyToVector()
    return {
        "seconds_per_stride_plain_simulation": t_plain,
        "plain_simulation_end_state": x_end.tolist(),
        "accuracy": accuracy,
        "integrator": "runge_kutta5 (error-controlled), max step 0.05 s",
        "slope": m.slope,
        "params": {
            "mass_hip": m.params.mass_hip(),
            "mass_leg": m.params.mass_leg(),
            "length_leg": m.params.length_leg(),
            "center_of_mass_leg": m.params.center_of_mass_leg(),
            "gravity": m.params.gravity(),
            "slope": m.params.slope(),
        },
        "steady_state_simulated": s_sim.tolist(),
        "steady_state_history": hist,
        "fixed_point": s.tolist(),
        "newton_residuals": newton,
        "period": period,
        "pre_impact_drake_state": x_pre.tolist(),
        "post_impact_drake_state": m.to_drake(s).tolist(),
        "multipliers_fd": mults,
        "fd_step_newton": h_fd,
        "seconds_per_stride_stride_map": t_stride,
    }


def main():
    accs = [float(a) for a in sys.argv[1:]] or [1e-6, 1e-8, 1e-10, 1e-12]
    guess = [0.2710, -1.0924, 0.7150]
    out = []
    for a in accs:
        t0 = time.perf_counter()
        r = run(a, guess)
        r["wall_s"] = time.perf_counter() - t0
        print(f"accuracy {a:.0e}: s* = {r['fixed_point']}, period {r['period']:.12f}, "
              f"{r['seconds_per_stride_plain_simulation'] * 1e3:.3f} ms/stride (plain), {r['seconds_per_stride_stride_map'] * 1e3:.2f} ms/stride (stride map), Newton {r['newton_residuals']}",
              file=sys.stderr)
        out.append(r)
    os.makedirs(OUT, exist_ok=True)
    with open(os.path.join(OUT, "drake.json"), "w") as f:
        json.dump({"command": "python3 experiments/drake_compass.py " + " ".join(sys.argv[1:]),
                   "runs": out}, f, indent=1)
    print("wrote", os.path.join(OUT, "drake.json"), file=sys.stderr)


if __name__ == "__main__":
    main()
