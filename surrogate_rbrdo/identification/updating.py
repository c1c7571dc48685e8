"""The experimenter's FE model at standstill with the factors an impact test updates: each
bearing's stiffness ``θ_b`` and damping ``d_b`` (``C_b ← d_b C_b``), and the tool/holder mass
``m`` — its matrices, undamped natural frequencies, and the accelerance at a DOF with its
analytic derivatives (:func:`~surrogate_rbrdo.identification.impact.impact_damping` fits them).

>>> from surrogate_rbrdo.spindle import reference_spindle
>>> sp = reference_spindle()
>>> sm = StandstillModel(sp.model(sp.baseline), "tool_holder")
>>> f = sm.natural_hz(np.ones(2), 1.0)
>>> round(float(f[f > 100][0]), 1)                 # the first bending mode (Hz)
362.7
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import numpy as np
from scipy.linalg import eigh

from surrogate_rbrdo.spindle.assembly import SpindleModel, build_model


@dataclass(frozen=True, eq=False)
class StandstillModel:
    """The experimenter's model with bearing stiffness factors, damping factors and a tool
    mass factor (module docstring)."""

    model: SpindleModel
    tool_disk: str | None

    def matrices(self, theta: np.ndarray, d: np.ndarray, m: float):
        mdl = self.model if self.tool_disk is None or m == 1.0 else with_tool_mass(
            self.model, self.tool_disk, m)
        M, C, K = mdl.system_matrices(0.0, theta)
        _, Cb = mdl.bearing_coefficients(np.zeros((1, 1)), theta[None])
        for j, node in enumerate(mdl.bearing_nodes):
            dofs = np.array([4 * node, 4 * node + 1])
            C[np.ix_(dofs, dofs)] += (d[j] - 1.0) * Cb[0, 0, j]
        return M, C, K

    def natural_hz(self, theta: np.ndarray, m: float) -> np.ndarray:
        M, _, K = self.matrices(theta, np.ones(theta.size), m)
        w2 = eigh(0.5 * (K + K.T), 0.5 * (M + M.T), eigvals_only=True)
        return np.sqrt(np.clip(w2, 0.0, None)) / (2 * np.pi)

    def accelerance(self, theta, d, m, s: np.ndarray, dof: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
        """``H = s² [K + sC + s²M]⁻¹`` at ``(dof_i, dof_i)`` for each ``s_i``, and its
        derivatives ``(F, 2 nb [+ 1])`` with respect to the logs of ``θ``, ``d`` (and ``m``):
        ``∂H/∂p = −s² xᵀ (∂A/∂p) x`` with ``x = A⁻¹ e`` (``A`` symmetric at standstill; the
        bearings' ``K_b`` and ``C_b = η K_b`` are proportional to ``θ_b``)."""
        M, C, K = self.matrices(theta, d, m)
        A = K[None] + s[:, None, None] * C[None] + (s**2)[:, None, None] * M[None]
        e = np.zeros((s.size, K.shape[0], 1), complex)
        e[np.arange(s.size), dof, 0] = 1.0
        x = np.linalg.solve(A, e)[:, :, 0]
        Kb, Cb = self.model.bearing_coefficients(np.zeros((1, 1)), theta[None])
        cols = []
        blocks = []
        for j, node in enumerate(self.model.bearing_nodes):
            xb = x[:, 4 * node:4 * node + 2]
            blocks.append((xb, Kb[0, 0, j], d[j] * Cb[0, 0, j]))
        cols += [np.einsum("fi,ij,fj->f", xb, kb, xb) + s * np.einsum("fi,ij,fj->f", xb, cb, xb)
                 for xb, kb, cb in blocks]
        cols += [s * np.einsum("fi,ij,fj->f", xb, cb, xb) for xb, _, cb in blocks]
        if self.tool_disk is not None:
            t = slice(4 * self.model.tool_node, 4 * self.model.tool_node + 4)
            # M and the mass-proportional damping αM: ∂A/∂m = (s² + α s) ∂M/∂m
            cols.append(m * (s**2 + self.model.alpha * s) * np.einsum(
                "fi,ij,fj->f", x[:, t], self._tool_mass_block, x[:, t]))
        return s**2 * x[np.arange(s.size), dof], -(s**2)[:, None] * np.stack(cols, axis=1)

    @functools.cached_property
    def _tool_mass_block(self) -> np.ndarray:
        """``∂M/∂m`` at the tool node (the tool disk's mass and inertias; linear in ``m``)."""
        t = slice(4 * self.model.tool_node, 4 * self.model.tool_node + 4)
        M2 = with_tool_mass(self.model, self.tool_disk, 2.0).system_matrices(0.0)[0]
        return (M2 - self.model.system_matrices(0.0)[0])[t, t]


def with_tool_mass(model: SpindleModel, disk: str, m: float) -> SpindleModel:
    """``model`` with the disk ``disk``'s mass and inertias scaled by ``m``."""
    g = model.geometry
    disks = tuple(replace(k, mass_kg=k.mass_kg * m, polar_inertia_kgm2=k.polar_inertia_kgm2 * m,
                          diametral_inertia_kgm2=k.diametral_inertia_kgm2 * m)
                  if k.name == disk else k for k in g.disks)
    return build_model(replace(g, disks=disks), model.effects,
                       theta_bearings=model.theta_bearings)


__all__ = ["StandstillModel", "with_tool_mass"]
