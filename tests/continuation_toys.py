"""Small fixed-point problems with exact answers, for the continuation engine's tests.

Each is a map z -> P(z, p) with r = P - z, its multipliers the eigenvalues of dP/dz.
"""

from __future__ import annotations

import math

import numpy as np

from impactbeams.continuation.problem import Evaluation, multipliers_of


class Map:
    """A map given by ``step(z, p)`` and its Jacobian ``jacobian(z, p)``; optional grazing."""

    def __init__(self, step, jacobian, gap=None, period=1):
        self.step, self.jac, self.gap, self.period = step, jacobian, gap, period

    def _iterate(self, z, p):
        """The end, the Jacobian, and z1 at each of the period's sections."""
        jacobian, sections = np.eye(len(z)), []
        for _ in range(self.period):
            sections.append(z[0])
            jacobian = self.jac(z, p) @ jacobian
            z = self.step(z, p)
        return z, jacobian, np.array(sections)

    def residual(self, z, p):
        return self._iterate(z, p)[0] - z

    def evaluate(self, z, p, jacobian=True, grazing=True):
        end, monodromy, _ = self._iterate(z, p)
        jacobian = monodromy - np.eye(len(z)) if jacobian else np.empty((0, 0))
        gap = math.nan if self.gap is None else self.gap(z, p)
        return Evaluation(end - z, jacobian,
                          multipliers_of(jacobian) if jacobian.size else np.empty(0),
                          grazing=gap if grazing else math.nan,
                          contacts=int(gap <= 0) if self.gap else 0)

    def measures(self, z, p):
        return {"amplitude": float(np.max(np.abs(z))),
                "section_deflection_1": self._iterate(z, p)[2]}

    def iterated(self, times):
        return Map(self.step, self.jac, self.gap, self.period * times)


def fold():
    """r1 = z1^2 + 0.04 z1 - p at z2 = 0.4 z1: a fold at z1 = -0.02, p = -4e-4 exactly."""
    return Map(lambda z, p: z + np.array([z[0] ** 2 - p + 0.1 * z[1], -0.5 * z[1] + 0.2 * z[0]]),
               lambda z, p: np.eye(2) + np.array([[2 * z[0], 0.1], [0.2, -0.5]]))


def period_doubling():
    """z1 -> -(1 + p) z1 + z1^3, z2 -> z2 / 2 + z1^2: the multiplier -(1 + p) crosses -1 at
    p = 0; the period-2 orbit is z1 = +-sqrt(p), z2 = 2 p."""
    return Map(lambda z, p: np.array([-(1 + p) * z[0] + z[0] ** 3, 0.5 * z[1] + z[0] ** 2]),
               lambda z, p: np.array([[-(1 + p) + 3 * z[0] ** 2, 0.0], [2 * z[0], 0.5]]))


THETA = 0.7


def neimark_sacker():
    """z -> (1 + p - |z|^2) R(theta) z: multipliers (1 + p) e^(+-i theta), |mu| = 1 at p = 0."""
    rotation = np.array([[math.cos(THETA), -math.sin(THETA)], [math.sin(THETA), math.cos(THETA)]])

    def step(z, p):
        return (1 + p - z @ z) * rotation @ z

    def jacobian(z, p):
        return (1 + p - z @ z) * rotation - 2 * np.outer(rotation @ z, z)

    return Map(step, jacobian)


def grazing(stiffness=100.0):
    """z -> z / 2 + p + K max(0, z - 1)^(3/2), gap 1 - z: grazing at p = 1/2, then a fold at
    z = 1 + 1/(9 K^2), p = 1/2 + 1/(54 K^2), where the multiplier 1/2 + 3/2 K sqrt(z - 1)
    reaches 1."""
    def step(z, p):
        return np.array([0.5 * z[0] + p + stiffness * max(0.0, z[0] - 1.0) ** 1.5])

    def jacobian(z, p):
        return np.array([[0.5 + 1.5 * stiffness * math.sqrt(max(0.0, z[0] - 1.0))]])

    return Map(step, jacobian, gap=lambda z, p: 1.0 - z[0])


def fold_then_grazing(offset=0.4, slant=0.0):
    """z -> z + (p - z^2) / 2: a fold at z = p = 0; the gap -(z + offset) + slant (z^2 - p),
    whose sign the branch p = z^2 changes at z = -offset, p = offset^2 only, past the fold
    coming from z > 0. Off the branch, ``slant`` > 0 makes the gap positive on the far side of
    the fold's parabola (where a step's predictor lands when it overshoots the fold)."""
    return Map(lambda z, p: z + 0.5 * (p - z ** 2), lambda z, p: np.array([[1.0 - z[0]]]),
               gap=lambda z, p: -(z[0] + offset) + slant * (z[0] ** 2 - p))


def pitchfork():
    """z1 -> z1 + (p z1 - z1^3) / 2, z2 -> z2 / 2 + z1^2: the branch z = 0 for every p, its
    multiplier 1 + p / 2 through +1 at p = 0, where the branch z1^2 = p, z2 = 2 p crosses it
    (symmetric under z1 -> -z1: a symmetry-breaking pitchfork); the branch never turns."""
    return Map(lambda z, p: np.array([z[0] + 0.5 * (p * z[0] - z[0] ** 3), 0.5 * z[1] + z[0] ** 2]),
               lambda z, p: np.array([[1.0 + 0.5 * (p - 3.0 * z[0] ** 2), 0.0], [2.0 * z[0], 0.5]]))


def colliding_pair(k=5.0):
    """z -> A(p) z, A = [[-1/2, 1], [k^2 p, -1/2]]: multipliers -1/2 +- i k sqrt(-p) for p < 0
    meet on the negative axis at p = 0 and split; -1/2 - k sqrt(p) reaches -1 at p = 1/(4 k^2)."""
    def matrix(p):
        return np.array([[-0.5, 1.0], [k * k * p, -0.5]])

    return Map(lambda z, p: matrix(p) @ z, lambda z, p: matrix(p))


class CurveMap:
    """A Neimark-Sacker curve of a map family z -> P(z; p1, p2), as `curves.CurveProblem` is:
    a family in p2 whose state is y = (z, p1), the residual (P - z, the condition's test
    function of ``condition.matrix(M)``). Its Jacobian in y by central differences (a toy's:
    exact to ~1e-10, which steers Newton only)."""

    period = 1

    def __init__(self, step, jacobian, condition):
        self.step, self.jac, self.condition = step, jacobian, condition

    def _residual(self, y, p):
        z, p1 = y[:-1], y[-1]
        return np.append(self.step(z, p1, p) - z,
                         self.condition.of(self.condition.matrix(self.jac(z, p1, p))))

    def evaluate(self, y, p, jacobian=True, grazing=True):
        residual = self._residual(y, p)
        monodromy = self.jac(y[:-1], y[-1], p)
        full = np.empty((0, 0))
        if jacobian:
            full = np.empty((y.size, y.size))
            for j in range(y.size):
                h = np.zeros(y.size)
                h[j] = 1e-6
                full[:, j] = (self._residual(y + h, p) - self._residual(y - h, p)) / 2e-6
        return Evaluation(residual, full, multipliers_of(monodromy - np.eye(len(monodromy))))

    def multipliers(self, y, p):
        monodromy = self.jac(y[:-1], y[-1], p)
        return multipliers_of(monodromy - np.eye(len(monodromy)))

    def measures(self, y, p):
        return {"amplitude": float(np.max(np.abs(y[:-1])))}

    def border(self, y, p, evaluation):
        monodromy = self.jac(y[:-1], y[-1], p)
        self.condition.border(monodromy - np.eye(len(monodromy)), np.ones(len(monodromy)))


def resonant_torus(fold_at):
    """(u, v) -> (1 + p1) A (u, v) with A = [[p2, 1], [p2^2 - 1, p2]] (det 1, trace 2 p2: the
    pair p2 +- sqrt(p2^2 - 1), on the unit circle with cos theta = p2 for |p2| < 1, real
    beyond), and x -> x + (p2 - ``fold_at``) - x^2 (fixed points x = +-sqrt(p2 - fold_at),
    multiplier 1 - 2 x, a fold at p2 = ``fold_at``). The Neimark-Sacker curve is p1 = 0:
    strong resonances 1:1, 1:2, 1:3, 1:4 at p2 = 1, -1, -1/2, 0, a fold-Neimark-Sacker point
    (the curve turning back in p2) at p2 = ``fold_at``."""

    def step(z, p1, p2):
        u, v, x = z
        s = 1.0 + p1
        return np.array([s * (p2 * u + v), s * ((p2 ** 2 - 1.0) * u + p2 * v),
                         x + (p2 - fold_at) - x ** 2])

    def jacobian(z, p1, p2):
        s = 1.0 + p1
        return np.array([[s * p2, s, 0.0], [s * (p2 ** 2 - 1.0), s * p2, 0.0],
                         [0.0, 0.0, 1.0 - 2.0 * z[2]]])

    return step, jacobian


def circle(radius=1.0):
    """z1 -> z1 + z1^2 + p^2 - radius^2, z2 -> z2 / 2: the branch is the circle z1^2 + p^2 =
    radius^2 (curvature 1 / radius in the unscaled unknowns), folds at p = +-radius."""
    return Map(lambda z, p: np.array([z[0] + z[0] ** 2 + p ** 2 - radius ** 2, 0.5 * z[1]]),
               lambda z, p: np.array([[1.0 + 2.0 * z[0], 0.0], [0.0, 0.5]]))
