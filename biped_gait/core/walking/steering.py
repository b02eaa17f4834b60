"""Momentum steering: the walker's per-step re-aim that also returns the one quantity the
impulses cannot set to the gait's value (docs/model.md section 8.7).

The re-aim of docs/model.md section 8.5 gives the next step its duration as the tenth unknown.
That leaves the angular momentum about the foot-to-foot line, which no impulse changes, to decay
by itself: about 1 % per step at the default gait (closed-loop multiplier 0.99). After a push
the walker walks on for hundreds of steps at another cadence before it is back on the orbit.

Steering frees one more unknown, the trunk pitch theta' of the next touchdown configuration
q_T(theta') = q_T + (theta' - theta_p) e_theta (e_theta = the configurations' ``theta_direction``:
the pelvis and trunk pitch forward, the legs stay), and adds one equation, a feedback law. With,
at touchdown k,

    M_k      the momentum about the foot-to-foot line, z_d^T D_e(q^-) [0; qd^-] (kg m^2/s), which
             the double support keeps into the next step,
    theta_k  the pelvis pitch of the touchdown configuration (rad): the sum of the stance leg's
             pitch coordinates (q2 + q3 + q4 with the paper's nine),

and the gait's M_p and theta_p, linearize the re-aim that aims at the plan's q_T (theta' =
theta_p): M_{k+1} - M_p = s_k, with

    s_k = a (theta_k - theta_p) + b (M_k - M_p),

a = d M_{k+1} / d theta_k (kg m^2/s per rad), b = d M_{k+1} / d M_k (the slow multiplier, about
0.99). s_k is the momentum error the plain re-aim would carry into the next touchdown. The law
chooses theta' so that this error contracts by the factor ``rate`` (rho) per step:

    a (theta' - theta_p) + b (M_{k+1} - M_p) = rho s_k           (M_{k+1} of the re-aimed step)

Linearized, the closed loop then has the multipliers rho and 0 (and those of the re-aim's other,
already dead-beat, modes): s_{k+1} = rho s_k, theta_{k+1} - theta_p = (rho - b) s_k / (a + b c),
c = d M_{k+1} / d theta' the pitch's authority over the momentum. a + b c is 23.8 kg m^2/s per
rad at the default gait; freeing the step length instead would give 0.4 kg m^2/s per m (a longer
step gains in one step what the next step from the longer stance loses), which is why the pitch
is the unknown freed. rho = 0 is dead-beat (two steps), larger rho spreads the correction and
asks for smaller pitch changes.

The nq + 2 equations (the nq of the touchdown configuration, the current impact's closure, the
law) in the nq + 2 unknowns (next initial velocity v, duration tau, pitch theta') are solved
by chord steps with the orbit's Jacobian (near the orbit: one or two steps), else by Newton's
method with the exact Jacobian of the computed flow; where that fails (after a push), by
continuations (``MomentumSteering.solve``). Where the law cannot be met but the plain re-aim
(theta' = theta_p) can, the step steers as far as it goes and the next one goes on.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..dynamics import newton
from ..dynamics.flow import BallisticFlow
from ..dynamics.hybrid import HybridStep, ImpactMap
from ..gait.configurations import boundary_configurations
from ..model.biped import BipedModel

DEFAULT_RATE = 0.25
"""rho: the momentum error's contraction per step (0: dead-beat). Of 0, 0.1, 0.25 and 0.35 at the
default gait, the gentler the steering, the larger the pushes recovered (forward 0.56, 0.65,
0.82, 0.99 N s at mid-step); 0.25 keeps a margin on 1e-3 of the orbit within 10 steps (a
distance of 5 shrinks to 2e-5)."""
TOLERANCE = 1e-12  # rad, kg m^2/s: as the plain re-aim (docs/model.md section 8.5)
COARSE_TOLERANCE = 1e-9  # where Newton on the coarse grid hands over to the walker's grid
CHORD_STEPS = 7
HOMOTOPY_STAGES = 8  # stages of the fallbacks' continuations
NEWTON_ITERATIONS = 30
DIRECT_ITERATIONS = 10  # the direct Newton's of a transition's first step and of a closure round: from
# their warm starts it converges in 1 to 8; far from the new orbit it wanders instead (the 13-DOF set's
# transitions in T: 30 iterations, half a second), and the continuation from the plain re-aim is cheaper
FD_STEP = 1e-6  # rad: central differences of the impact map's configuration dependence


class SteeringFailed(Exception):
    """The steered re-aim has no solution near the state: the message says which stage failed."""


def pelvis_pitch(bm: BipedModel, q: np.ndarray) -> float:
    """The sum of the stance leg's pitch coordinates, the ankle's, the knee's and the hip's (q2 +
    q3 + q4 with the paper's nine; rad): the pelvis pitch, theta at a double-support configuration."""
    return float(q[bm.index("ankle_pitch")] + q[bm.index("knee")] + q[bm.index("hip_pitch")])


@dataclass(frozen=True, eq=False)
class SteeringReference:
    """The gait step the re-aim steers to, linearized on its orbit: touchdown configuration q_T
    (rad), initial and final velocities (rad/s), duration (s), trunk pitch theta_p (rad),
    momentum about the foot-to-foot line at its touchdown M_p (kg m^2/s), the gains a (kg m^2/s
    per rad) and b (-) of s, the chord Jacobian of the nq + 2 equations on the orbit, e_theta
    (nq), how the touchdown configuration moves with the pitch, and the touchdown the step starts
    from on the orbit (a periodic gait's own; in a stride, the other step's): its configuration
    (rad), pre-impact velocity (rad/s), pitch (rad) and momentum (kg m^2/s)."""

    q_t: np.ndarray
    qd_a: np.ndarray
    qd_b: np.ndarray
    period: float
    theta: float
    momentum: float
    a: float
    b: float
    jacobian: np.ndarray
    direction: np.ndarray
    start_q_t: np.ndarray
    start_qd_b: np.ndarray
    start_theta: float
    start_momentum: float

    @property
    def authority(self) -> float:
        """a + b c (kg m^2/s per rad): how much the next touchdown's pitch, held there over the
        following step, moves the momentum error s; the law's diagonal. Where it vanishes the
        pitch cannot steer the momentum (docs/model.md section 8.8)."""
        return float(self.jacobian[-1, -1])

    def error(self, bm: BipedModel, q_pre: np.ndarray, momentum: float) -> float:
        """s (kg m^2/s) of a touchdown at ``q_pre`` with momentum ``momentum`` about the feet line
        that starts this step."""
        return self.a * (pelvis_pitch(bm, q_pre) - self.start_theta) + self.b * (momentum - self.start_momentum)


def momentum_row(hybrid: HybridStep, q: np.ndarray) -> np.ndarray:
    """The single-support part of z_d^T D_e at the double-support configuration ``q``: qd (rad/s)
    -> momentum about the foot-to-foot line (kg m^2/s)."""
    return hybrid.impact(q).momentum_row[hybrid.bm.ds_of_single]


def planned_momentum(hybrid: HybridStep, orbit) -> float:
    """The momentum about the foot-to-foot line at ``orbit``'s touchdown (kg m^2/s; a
    ``PlannedOrbit``)."""
    return float(momentum_row(hybrid, np.asarray(orbit.q_t)) @ np.asarray(orbit.qd_b))


def _theta_derivative(f, q: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """d f(q + t e_theta) / d t at t = 0, by central differences (``FD_STEP``)."""
    return (f(q + FD_STEP * direction) - f(q - FD_STEP * direction)) / (2 * FD_STEP)


def reference(hybrid: HybridStep, flow: BallisticFlow, q0: np.ndarray, q_t: np.ndarray, qd_a: np.ndarray,
              qd_b: np.ndarray, period: float, direction: np.ndarray | None = None,
              previous: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> SteeringReference:
    """The linearization of the orbit from (``q0``, ``qd_a``) to (``q_t``, ``qd_b``) in
    ``period`` (s) on ``flow``'s grid: one integration with its sensitivity Phi to the initial
    velocity and to the initial configuration along e_theta. ``direction``: e_theta at q_T (default
    the straight gaits', ``BoundaryConfigurations.theta_direction``); ``previous``: the touchdown
    configuration, velocity and e_theta of the step before, whose touchdown starts this one
    (default this step's own: a periodic gait).

    a and b from the plain re-aim (unknowns dv, dtau; the start's pitch dtheta_s and momentum
    dM_s given): Phi_qq e_s dtheta_s + Phi_qv dv + qd_b dtau = 0, (dg/dtheta_s qd_a) dtheta_s +
    g dv - dM_s = 0, and dM' = r (Phi_vq e_s dtheta_s + Phi_vv dv + qdd_b dtau), with g the
    closure's gain (d momentum after / d v) at the starting touchdown, e_s its e_theta carried
    through the leg exchange, and r the momentum row at q_T."""
    bm = hybrid.bm
    n = bm.nq
    e_theta = boundary_configurations(bm).theta_direction if direction is None else np.asarray(direction)
    if previous is None:
        q_p, qd_p, e_p, e_start = q_t, qd_b, e_theta, e_theta
    else:
        q_p, qd_p, e_p = (np.asarray(x) for x in previous)
        e_start = _theta_derivative(hybrid.exchange.configuration, q_p, e_p)
    seeds = np.zeros((2 * n, n + 1))
    seeds[:n, 0], seeds[n:, 1:] = e_start, np.eye(n)
    sens = flow.propagate(q0, qd_a, period, seeds).sens
    phi_theta, phi = sens[:, 0], sens[:, 1:]  # d(q, qd)(T) / d theta_s along e_s, and / d qd(0)
    qdd_b = flow.acceleration(q_t, qd_b)
    gain = hybrid.impact(q_p).closure_gradients()[0]
    gain_theta = _theta_derivative(lambda q: hybrid.impact(q).closure_gradients()[0], q_p, e_p) @ qd_a
    row = momentum_row(hybrid, q_t)
    plain = np.zeros((n + 1, n + 1))
    plain[:n, :n], plain[:n, n], plain[n, :n] = phi[:n], qd_b, gain
    forcing = np.zeros((n + 1, 2))  # columns: dtheta_s, dM_s
    forcing[:n, 0], forcing[n, 0], forcing[n, 1] = phi_theta[:n], gain_theta, -1.0
    response = -np.linalg.solve(plain, forcing)  # (dv, dtau) per (dtheta_s, dM_s)
    d_qd = phi[n:] @ response[:n] + np.outer(qdd_b, response[n])  # d qd(tau) per (dtheta_s, dM_s)
    d_qd[:, 0] += phi_theta[n:]
    a, b = row @ d_qd
    jacobian = np.zeros((n + 2, n + 2))
    jacobian[:n + 1, :n + 1] = plain
    jacobian[:n, n + 1] = -e_theta
    jacobian[n + 1, :n], jacobian[n + 1, n] = b * row @ phi[n:], b * row @ qdd_b
    jacobian[n + 1, n + 1] = a + b * _theta_derivative(lambda q: momentum_row(hybrid, q), q_t, e_theta) @ qd_b
    return SteeringReference(q_t, qd_a, qd_b, period, pelvis_pitch(bm, q_t), float(row @ qd_b), float(a), float(b),
                             jacobian, e_theta, q_p, qd_p, pelvis_pitch(bm, q_p), float(momentum_row(hybrid, q_p) @ qd_p))


class MomentumSteering:
    """The steered re-aim towards ``ref`` with contraction ``rate`` (rho, in [0, 1)) on
    ``flow``'s grid (the walker's); Newton's iterations run on ``coarse`` (a coarser grid of the
    same flow, or None for ``flow`` itself) and are finished on ``flow`` by chord steps.
    ``transition``: its first step comes from another gait, whose last solution (v, tau,
    theta') was ``transition`` away from that gait's (qd_a, T, theta_p): no chord steps with the
    orbit's Jacobian then (they only reach a state near the orbit), and Newton starts from this
    gait's values moved by that offset (in a ramp of transitions, each much like the last, that
    halves Newton's iterations). ``offset``: the same of this steering's last solution."""

    def __init__(self, hybrid: HybridStep, flow: BallisticFlow, ref: SteeringReference, rate: float = DEFAULT_RATE,
                 coarse: BallisticFlow | None = None, transition: np.ndarray | None = None):
        if not 0.0 <= rate < 1.0:
            raise ValueError(f"the momentum steering rate must be in [0, 1), got {rate}")
        self.hybrid, self.flow, self.ref, self.rate = hybrid, flow, ref, rate
        self.coarse = coarse or flow
        self.transition = transition
        self.offset = np.zeros(hybrid.bm.nq + 2)
        self._last: tuple[np.ndarray, float] | None = None  # the last solution (v, tau, theta') and its law's value

    def solve(self, q_pre: np.ndarray, impact: ImpactMap, xd_b: np.ndarray, duration: float,
              foot_line_moment: float = 0.0, again: bool = False) -> tuple[np.ndarray, float, float]:
        """The next step's initial velocity v (its own coordinates, rad/s), duration tau (s) and
        touchdown pitch theta' (rad), from the touchdown at ``q_pre`` (rad) whose impact map is
        ``impact`` and pre-impact velocity ``xd_b`` (extended, rad/s); ``duration``: the warm
        start of tau; ``foot_line_moment``: what the ground's spin moments change of the momentum
        about the feet line (kg m^2/s, ``PlannedOrbit``); ``again``: the same touchdown as the
        last solve, with another ``foot_line_moment`` (the walker's closure rounds).
        ``SteeringFailed`` if no stage finds a step.

        Stages, each tried when the ones before fail: ``again``, Newton from the last solution
        with the law as far as it was met there (the solution moves by what the spin moments
        changed: one or two iterations); chord steps on the
        walker's grid with the orbit's Jacobian (not for a transition's first step); Newton with
        the law from the orbit's values (moved by the last gait's offset, for a transition's first
        step); the plain re-aim (theta' = theta_p) by Newton, then the law reached from it in
        ``HOMOTOPY_STAGES`` stages of its right-hand side, as far as it goes (a step that steers
        less this time, rather than none); last, the law along ``HOMOTOPY_STAGES`` touchdowns
        between the orbit's and this one. Newton runs on the coarse grid, finished by chord steps
        (else Newton) on the walker's."""
        equations = _Equations(self, q_pre, impact, xd_b, foot_line_moment)
        x0 = np.concatenate([self.ref.qd_a, [duration, self.ref.theta]])
        x = None
        if again and self._last is not None:
            last, law = self._last
            equations.law, full = law, equations.law
            result = equations.solve(last, free_pitch=True, iterations=DIRECT_ITERATIONS)
            x = result.x if result.converged else None
            equations.law = equations.law if x is not None else full
        if x is None and self.transition is None:  # the chord steps reach only a state near the orbit
            result = newton.chord(lambda x: equations(x, False)[::2], x0, self.ref.jacobian, TOLERANCE, CHORD_STEPS,
                                  contraction=0.1)
            x = result.x if result.converged else None
        iterations = NEWTON_ITERATIONS if self.transition is None else DIRECT_ITERATIONS
        if x is None:
            result = equations.solve(x0 if self.transition is None else x0 + self.transition, free_pitch=True,
                                     iterations=iterations)
            x = result.x if result.converged else None
        self.transition = None
        if x is None:
            x = self._from_plain(equations, x0, iterations)
        if x is None:
            x = self._from_orbit(q_pre, impact, xd_b, x0, foot_line_moment)
        if x is None:
            raise SteeringFailed("re-aiming the next step failed (no solution found): the state is too far from the plan")
        n = self.hybrid.bm.nq
        if not x[n] > 0:
            raise SteeringFailed("re-aiming the next step gave a duration <= 0: the state is too far from the plan")
        self.offset = x - np.concatenate([self.ref.qd_a, [self.ref.period, self.ref.theta]])
        self._last = (x, equations.law)
        return x[:n], float(x[n]), float(x[n + 1])

    def _from_plain(self, equations: "_Equations", x0: np.ndarray, iterations: int = NEWTON_ITERATIONS
                    ) -> np.ndarray | None:
        """The plain re-aim, then the law's right-hand side moved from the plain solution's value
        to the law's in stages (Newton's ``iterations`` each); the last stage solved (None if the
        plain re-aim fails), with ``equations.law`` the right-hand side it meets."""
        plain = equations.solve(x0, free_pitch=False)
        if not plain.converged:
            return None
        law, x = equations.law, plain.x
        start = reached = float(equations(x, False)[0][-1]) + law  # the law's left-hand side at the plain solution
        for fraction in np.linspace(0.0, 1.0, HOMOTOPY_STAGES + 1)[1:]:
            equations.law = start + fraction * (law - start)
            stage = equations.solve(x, free_pitch=True, iterations=iterations)
            if not stage.converged:
                break
            x, reached = stage.x, equations.law
        equations.law = reached
        return x

    def _from_orbit(self, q_pre: np.ndarray, impact: ImpactMap, xd_b: np.ndarray, x0: np.ndarray,
                    foot_line_moment: float) -> np.ndarray | None:
        """The law along touchdowns from the orbit's (the step's starting touchdown and its
        momentum) to (``q_pre``, its momentum) in stages, each from the last; None if a stage
        fails."""
        ref, x = self.ref, x0
        momentum = float(impact.momentum_row @ xd_b)
        for fraction in np.linspace(0.0, 1.0, HOMOTOPY_STAGES + 1)[1:]:
            q = ref.start_q_t + fraction * (q_pre - ref.start_q_t)
            stage_impact = self.hybrid.impact(q)
            row = momentum_row(self.hybrid, q)
            target = ref.start_momentum + fraction * (momentum - ref.start_momentum)
            qd = ref.start_qd_b + (target - row @ ref.start_qd_b) * row / (row @ row)  # the stage's momentum about the feet line
            stage = _Equations(self, q, stage_impact, self.hybrid.bm.embed(qd), foot_line_moment).solve(x, free_pitch=True)
            if not stage.converged:
                return None
            x = stage.x
        return x


class _Equations:
    """The steered re-aim's equations from one touchdown (``MomentumSteering.solve``)."""

    def __init__(self, steering: MomentumSteering, q_pre: np.ndarray, impact: ImpactMap, xd_b: np.ndarray,
                 foot_line_moment: float) -> None:
        self.steering, self.ref = steering, steering.ref
        self.momentum = float(impact.momentum_row @ xd_b)
        self.kept = self.momentum - foot_line_moment  # the momentum the next step starts with
        self.law = steering.rate * self.ref.error(steering.hybrid.bm, q_pre, self.momentum)
        self.gain = impact.closure_gradients()[0]
        self.q_start = steering.hybrid.exchange.configuration(q_pre)

    def __call__(self, x: np.ndarray, jacobian: bool, free_pitch: bool = True, flow: BallisticFlow | None = None):
        """F (nq + 2, or nq + 1 with theta' = theta_p), dF/dx when ``jacobian``, on ``flow``
        (default the walker's grid); ``x`` = (v, tau, theta') or (v, tau)."""
        ref, hybrid = self.ref, self.steering.hybrid
        q_n = hybrid.bm.nq
        flow = flow or self.steering.flow
        v, tau, theta = x[:q_n], x[q_n], (x[q_n + 1] if free_pitch else ref.theta)
        n = q_n + 2 if free_pitch else q_n + 1
        if not tau > 0:
            return np.full(n, np.nan), None, None
        with np.errstate(over="ignore", invalid="ignore"):
            seeds = np.vstack([np.zeros((q_n, q_n)), np.eye(q_n)]) if jacobian else None
            run = flow.propagate(self.q_start, v, tau, seeds)
        target = ref.q_t + (theta - ref.theta) * ref.direction
        f = np.append(run.q - target, self.gain @ v - self.kept)
        if free_pitch:
            row = momentum_row(hybrid, target)
            f = np.append(f, ref.a * (theta - ref.theta) + ref.b * (row @ run.qd - ref.momentum) - self.law)
        if not jacobian or not np.all(np.isfinite(f)):
            return f, None, None
        jac = np.zeros((n, n))
        jac[:q_n, :q_n], jac[:q_n, q_n], jac[q_n, :q_n] = run.sens[:q_n], run.qd, self.gain
        if free_pitch:
            qdd = flow.acceleration(run.q, run.qd)
            jac[:q_n, q_n + 1] = -ref.direction
            jac[q_n + 1, :q_n], jac[q_n + 1, q_n] = ref.b * row @ run.sens[q_n:], ref.b * row @ qdd
            jac[q_n + 1, q_n + 1] = ref.a + ref.b * _theta_derivative(lambda q: momentum_row(hybrid, q), target,
                                                                       ref.direction) @ run.qd
        return f, jac, None

    def solve(self, x0: np.ndarray, free_pitch: bool, iterations: int = NEWTON_ITERATIONS) -> newton.SolveResult:
        """Newton from ``x0`` on the coarse grid (at most ``iterations``), finished by chord steps
        on the walker's grid with the last coarse Jacobian, else by Newton there. The result's x
        always has theta'."""
        q_n = self.steering.hybrid.bm.nq
        n = q_n + 2 if free_pitch else q_n + 1
        coarse, fine = self.steering.coarse, self.steering.flow

        def on(flow: BallisticFlow):
            return lambda x, jacobian: self(x, jacobian, free_pitch, flow)

        tol = TOLERANCE if coarse is fine else COARSE_TOLERANCE
        result = newton.newton(on(coarse), x0[:n], tol, iterations)
        if result.converged and coarse is not fine:
            finish = newton.chord(lambda x: on(fine)(x, False)[::2], result.x, result.jacobian, TOLERANCE,
                                  CHORD_STEPS, contraction=0.1)
            result = finish if finish.converged else newton.newton(on(fine), result.x, TOLERANCE, NEWTON_ITERATIONS)
        return result if free_pitch else replace(result, x=np.append(result.x, self.ref.theta))
