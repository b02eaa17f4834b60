"""The yardsticks the benchmarks print their figures beside, each measured in the same run:

- ``ColdSolve``: the straightforward cold solve of one gait, written here independently of the
  project's solver: damped Newton shooting on qd(0) from the straight-line start, each iterate one
  integration of the ballistic dynamics with its variational equations by SciPy's adaptive
  DOP853 (``solve_ivp``), accelerations and their derivatives from Pinocchio's ABA; then the
  double support's minimum-effort impulses (eqs. 6-10, W = sum |I-| + |I+|) as a linear program
  solved by HiGHS (SciPy's ``linprog``). It takes from the project only the biped as data: the
  Pinocchio models built from the parameter file, the double-support configurations at trunk
  pitch theta = 0 (the paper's gait, its cycle closed by the correction s along the locked
  rotation, docs/model.md section 4) and the leg exchange P.
- ``import_floor_s``: a Python process that only imports NumPy, SciPy, Pinocchio and highspy.

``REFERENCE_COLD_SOLVE_S`` says what the reference machine is: the one where the cold solve takes
that long (issue 21 measured the simulator at 28.8x real time on a machine where the cold solve
took about 0.1 s, and put it at 14x at the reference speed: about half as fast);
``at_reference`` scales a speed (a real-time factor) measured here to it.
"""

from __future__ import annotations

import math
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp
from scipy.optimize import linprog

from biped_gait.core.gait.configurations import GaitMode, boundary_configurations
from biped_gait.core.model.biped import STANCE_TIP, SWING_TIP, BipedModel
from biped_gait.core.model.exchange import exchange_matrix
from biped_gait.core.model.params import load_params

REFERENCE_COLD_SOLVE_S = 0.2  # s: the cold solve on the reference machine (issue 21)
FLOOR_IMPORTS = "import numpy, scipy, pinocchio, highspy"
TOLERANCE = 1e-9  # rad: |q(T) - q_T| at convergence
MAX_ITERATIONS = 20


def median_s(call, repeat: int) -> float:
    """Median wall time (s) of ``call()`` over ``repeat`` calls."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def at_reference(speed: float, cold_solve_s: float) -> float:
    """``speed`` measured on a machine whose cold solve takes ``cold_solve_s`` (s), scaled to the
    reference machine's: a machine twice as fast as the reference (its cold solve half as long)
    runs twice as fast."""
    return speed * cold_solve_s / REFERENCE_COLD_SOLVE_S


def import_floor_s(repeat: int = 5) -> float:
    """Median wall time (s) of a Python process that imports NumPy, SciPy, Pinocchio and highspy."""
    return median_s(lambda: subprocess.run([sys.executable, "-c", FLOOR_IMPORTS], check=True), repeat)


@dataclass(frozen=True)
class ColdSolution:
    """The yardstick's gait: qd(0) (rad/s), its Newton iterations, W (N m s), s (rad/s)."""

    qd0: np.ndarray
    iterations: int
    W: float
    slack: float


class ColdSolve:
    """The straightforward cold solve of the gait (L m, T s, alpha rad, mode) at theta = 0."""

    def __init__(self, step_length: float = 0.45, period: float = 0.45, alpha: float = math.radians(23.5),
                 mode: GaitMode = GaitMode.NORMAL) -> None:
        bm = BipedModel.from_params(load_params())
        self.single, self.extended = bm.single, bm.extended
        self.data, self.extended_data = self.single.createData(), self.extended.createData()
        self.period = period
        self.q0, self.q_t = boundary_configurations(bm)(step_length, alpha, mode, 0.0)
        self.exchange_inverse = np.linalg.inv(exchange_matrix(bm.coordinates))
        self._zero = np.zeros(self.single.nv)

    def _rhs(self, _t: float, y: np.ndarray) -> np.ndarray:
        """d/dt of [q, qd, S_q, S_qd], S = d(q, qd) / d qd(0) (two 9 x 9 blocks, row-major)."""
        n = self.single.nq
        s_q, s_qd = y[2 * n:2 * n + n * n].reshape(n, n), y[2 * n + n * n:].reshape(n, n)
        dq, dqd, _ = pin.computeABADerivatives(self.single, self.data, y[:n], y[n:2 * n], self._zero)
        return np.concatenate([y[n:2 * n], self.data.ddq, y[2 * n + n * n:], (dq @ s_q + dqd @ s_qd).ravel()])

    def _shoot(self, qd0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q(T), qd(T) and d q(T) / d qd(0) from (q0, qd0)."""
        n = self.single.nq
        y0 = np.concatenate([self.q0, qd0, np.zeros(n * n), np.eye(n).ravel()])
        end = solve_ivp(self._rhs, (0.0, self.period), y0, method="DOP853", rtol=1e-10, atol=1e-10).y[:, -1]
        return end[:n], end[n:2 * n], end[2 * n:].reshape(2 * n, n)[:n]

    def solve(self) -> ColdSolution:
        """Damped Newton on qd(0) from the straight-line start (each step halved until the
        residual's max-norm decreases), then the impulse LP."""
        qd0 = (self.q_t - self.q0) / self.period
        q_end, qd_end, jacobian = self._shoot(qd0)
        norm = np.max(np.abs(q_end - self.q_t))
        for iteration in range(MAX_ITERATIONS):
            if norm < TOLERANCE:
                return self._impulses(qd0, qd_end, iteration)
            step = np.linalg.solve(jacobian, q_end - self.q_t)
            for damping in 0.5 ** np.arange(10):
                trial = qd0 - damping * step
                shot = self._shoot(trial)
                if np.max(np.abs(shot[0] - self.q_t)) < norm:
                    break
            qd0, (q_end, qd_end, jacobian) = trial, shot
            norm = np.max(np.abs(q_end - self.q_t))
        raise RuntimeError("the yardstick's cold solve did not converge")

    def _impulses(self, qd0: np.ndarray, qd_end: np.ndarray, iterations: int) -> ColdSolution:
        """min sum |I-| + |I+| over (Xd-, I-, IR1-, Xd+, IR2, I+, IR2+, s, t) subject to eqs. (6)-(10)
        with the next step's start corrected by s along the locked rotation, |I| <= t and the
        reactions' vertical components non-negative (HiGHS through ``linprog``)."""
        model, data = self.extended, self.extended_data
        x = np.concatenate([np.zeros(3), self.q_t])
        d = pin.crba(model, data, x)
        d = np.triu(d) + np.triu(d, 1).T
        pin.computeJointJacobians(model, data, x)
        pin.updateFramePlacements(model, data)
        j1, j2 = (pin.getFrameJacobian(model, data, model.getFrameId(name), pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:3]
                  for name in (STANCE_TIP, SWING_TIP))
        tip = data.oMf[model.getFrameId(SWING_TIP)].translation
        z = np.zeros(12)
        z[3:5] = tip[:2] / np.linalg.norm(tip)  # unit rotation about the foot-to-foot line
        xd_b = np.concatenate([np.zeros(3), qd_end])
        qd_next = self.exchange_inverse @ qd0
        xd_a = np.concatenate([-j2[:, 3:] @ qd_next, qd_next])
        b_e = np.vstack([np.zeros((5, 7)), np.eye(7)])
        o = np.zeros
        # Columns: Xd- 12 | I- 7 | IR1- 3 | Xd+ 12 | IR2 3 | I+ 7 | IR2+ 3 | s 1; rows: eqs. (6)-(10)
        a_eq = np.block([
            [d, -b_e, -j1.T, o((12, 12)), o((12, 3)), o((12, 7)), o((12, 3)), o((12, 1))],
            [j1, o((3, 7)), o((3, 3)), o((3, 12)), o((3, 3)), o((3, 7)), o((3, 3)), o((3, 1))],
            [-d, o((12, 7)), o((12, 3)), d, -j2.T, o((12, 7)), o((12, 3)), o((12, 1))],
            [o((3, 12)), o((3, 7)), o((3, 3)), j2, o((3, 3)), o((3, 7)), o((3, 3)), o((3, 1))],
            [o((12, 12)), o((12, 7)), o((12, 3)), -d, o((12, 3)), -b_e, -j2.T, (d @ z)[:, None]],
        ])
        b_eq = np.concatenate([d @ xd_b, j1 @ xd_b, np.zeros(15), -d @ xd_a])
        n_x, n_t = a_eq.shape[1], 14
        impulses = np.zeros((n_t, n_x))
        impulses[:7, 12:19] = np.eye(7)
        impulses[7:, 37:44] = np.eye(7)
        a_ub = np.block([[impulses, -np.eye(n_t)], [-impulses, -np.eye(n_t)]])
        bounds = [(None, None)] * n_x + [(0.0, None)] * n_t
        for vertical in (21, 36, 46):  # the z components of IR1-, IR2, IR2+
            bounds[vertical] = (0.0, None)
        result = linprog(np.concatenate([np.zeros(n_x), np.ones(n_t)]), A_ub=a_ub, b_ub=np.zeros(2 * n_t),
                         A_eq=np.hstack([a_eq, np.zeros((len(a_eq), n_t))]), b_eq=b_eq, bounds=bounds, method="highs")
        if result.status != 0:
            raise RuntimeError(f"the yardstick's impulse LP failed: {result.message}")
        return ColdSolution(qd0, iterations, float(result.fun), float(result.x[47]))


def cold_solve_s(repeat: int = 5) -> float:
    """Median wall time (s) of the straightforward cold solve (after one untimed solve)."""
    solve = ColdSolve()
    solve.solve()
    return median_s(solve.solve, repeat)
