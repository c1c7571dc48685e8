"""The four design strategies, registered in :data:`~.base.FORMULATIONS`.

=================  ===================  ==========================================
name               objectives           constraints (all ``<= 0``)
=================  ===================  ==========================================
``deterministic``  max_k y(x, θ_k)      g_det
``rdo``            μ_y, σ_y             g_det
``rbdo``           μ_y                  P_f / P_target − 1, g_det
``rbrdo``          μ_y, σ_y             P_f / P_target − 1, g_det
=================  ===================  ==========================================

>>> sorted(FORMULATIONS)
['deterministic', 'rbdo', 'rbrdo', 'rdo']
>>> FORMULATIONS["rbrdo"].objective_names
('mean', 'std')
"""

from __future__ import annotations

from dataclasses import dataclass

from surrogate_rbrdo.formulations.base import FORMULATIONS, Formulation


@FORMULATIONS.register("deterministic")
@dataclass(frozen=True, eq=False)
class DeterministicFormulation(Formulation):
    """Minimise the response at the design-basis θ (the worst of its rows: a problem's stated
    design cases, or the image of ``u = 0``) subject to g_det only."""

    name = "deterministic"
    objective_names = ("nominal",)
    nominal_only = True


@FORMULATIONS.register("rdo")
@dataclass(frozen=True, eq=False)
class RDOFormulation(Formulation):
    """Robust design: minimise [μ_y, σ_y], no reliability constraint."""

    name = "rdo"
    objective_names = ("mean", "std")


@FORMULATIONS.register("rbdo")
@dataclass(frozen=True, eq=False)
class RBDOFormulation(Formulation):
    """Reliability-based design: minimise μ_y s.t. P_f <= P_target."""

    name = "rbdo"
    objective_names = ("mean",)
    reliability = True


@FORMULATIONS.register("rbrdo")
@dataclass(frozen=True, eq=False)
class RBRDOFormulation(Formulation):
    """Reliability-based robust design: minimise [μ_y, σ_y] s.t. P_f <= P_target."""

    name = "rbrdo"
    objective_names = ("mean", "std")
    reliability = True
