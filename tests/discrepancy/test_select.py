"""The forward selection's control flow (``selection.select``) with the stages stubbed: what a
group the encompassing test cannot separate from a generic change becomes under each
``generic_confound`` policy, and that the residual tests then run on the model carried."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy import selection, workflow
from surrogate_rbrdo.discrepancy.naming import Assessment
from surrogate_rbrdo.discrepancy.rivals import RivalTest
from surrogate_rbrdo.discrepancy.selection import select
from surrogate_rbrdo.discrepancy.soak import SoakTest
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyOptions

SPRING = "grounded spring at node 4 beside bearing front"


def _assessment(name: str, *, separable: bool, rival_adds: float = 0.1) -> Assessment:
    """A passing candidate whose closest rival is a spring: separable (the candidate adds
    20 > 6.63 to it) or not (0.5), the rival adding ``rival_adds`` to the candidate."""
    rt = RivalTest(20.0 if separable else 0.5, 6.63, SPRING, 30.0, rival_adds=rival_adds)
    fit = SimpleNamespace(fit=SimpleNamespace(label=f"fit of {name}"))
    return Assessment(name, 30.0, 1e-4, 1e-3, fit, {}, {"likelihood_ratio": True}, rt)


def _run(monkeypatch, groups, policy="unnamed_residual", max_effects=2):
    """``select`` with ``decide`` answering ``groups`` stage by stage; returns the selection
    and the candidate names each stage was given."""
    given = []

    def run_stage(train, current, cands, ho, **kw):
        given.append((current, tuple(c.name for c in cands)))
        return SimpleNamespace(index=len(given) - 1)

    monkeypatch.setattr(selection, "run_stage", run_stage)
    monkeypatch.setattr(selection, "decide", lambda st, delta: list(groups[st.index]))
    cands = tuple(SimpleNamespace(name=n) for n in ("thermal_preload", "housing", "gyroscopics"))
    opts = DiscrepancyOptions(generic_confound=policy, max_effects=max_effects)
    base = SimpleNamespace(label="base")
    sel = select(None, base, cands, None, opts, np.random.default_rng(0))
    return sel, given, base


@pytest.mark.parametrize("rival_adds", [0.1, 50.0])
def test_the_default_withholds_a_group_a_generic_change_mimics(monkeypatch, rival_adds):
    tp = _assessment("thermal_preload", separable=False, rival_adds=rival_adds)
    sel, given, base = _run(monkeypatch, [[tp]])
    assert sel.withheld == (tp,) and sel.confounded == () and sel.named == ()
    assert sel.current is base and len(sel.stages) == 1 and sel.generic == ()


def test_a_mutual_group_is_a_confounded_set_whose_fit_the_residual_tests_judge(monkeypatch):
    tp = _assessment("thermal_preload", separable=False)
    hs = _assessment("housing", separable=False, rival_adds=50.0)
    sel, given, _ = _run(monkeypatch, [[tp, hs], []], policy="confounded")
    assert sel.confounded == (tp, hs) and sel.withheld == () and sel.named == ()
    assert sel.generic == (SPRING,)                    # only the mutual members' rivals
    assert sel.current is tp.fit.fit
    # a second stage with no candidates, on the carried fit: the residual tests only
    assert len(sel.stages) == 2 and given[1] == (tp.fit.fit, ())


def test_a_rival_that_explains_more_withholds_under_either_policy(monkeypatch):
    tp = _assessment("thermal_preload", separable=False, rival_adds=50.0)
    sel, _, base = _run(monkeypatch, [[tp]], policy="confounded")
    assert sel.withheld == (tp,) and sel.confounded == () and sel.current is base


def test_after_a_name_a_mutual_group_leaves_the_names_standing(monkeypatch):
    hs = _assessment("housing", separable=True)
    tp = _assessment("thermal_preload", separable=False)
    for policy in ("unnamed_residual", "confounded"):
        sel, given, _ = _run(monkeypatch, [[hs], [tp]], policy=policy)
        assert sel.named == (hs,) and sel.withheld == () and sel.confounded == ()
        assert sel.current is hs.fit.fit and len(sel.stages) == 2
        assert given[1][1] == ("thermal_preload", "gyroscopics")


def test_a_separable_group_is_named_and_the_last_stage_has_no_candidates(monkeypatch):
    hs = _assessment("housing", separable=True)
    sel, given, _ = _run(monkeypatch, [[hs], []], max_effects=1)
    assert sel.named == (hs,) and len(sel.stages) == 2 and given[1][1] == ()
    assert sel.generic == () and sel.current is hs.fit.fit


# ---- the thermal soak as the separating test (selection._soaked) ---------------------------

def _drifting(name: str, *, separable: bool, drifts: bool) -> Assessment:
    """As :func:`_assessment`, with the candidate's effect class (drifting or not) and a slot."""
    a = _assessment(name, separable=separable)
    cls = SimpleNamespace(thermal_params=("b",) if drifts else ())
    a.fit.slot = SimpleNamespace(candidate=SimpleNamespace(effect_cls=cls), scope=())
    return a


def _soak_run(monkeypatch, groups, outcomes, soaks=("soak",)):
    """``_run`` with a soak in the data whose test answers ``outcomes[name]``."""
    asked = []

    def soak_test(train, current, fit, name, blocks, level):
        asked.append(name)
        return SoakTest(name, outcomes[name], 1.0, (12, 13), 0.5, 1.0, 0.1, 3, 0.5, 0.5,
                        0.1, level, 4)

    monkeypatch.setattr(selection, "soak_test", soak_test)
    given = []

    def run_stage(train, current, cands, ho, **kw):
        given.append(tuple(c.name for c in cands))
        return SimpleNamespace(index=len(given) - 1)

    monkeypatch.setattr(selection, "run_stage", run_stage)
    monkeypatch.setattr(selection, "decide", lambda st, delta: list(groups[st.index]))
    cands = tuple(SimpleNamespace(name=n) for n in ("thermal_preload", "housing", "gyroscopics"))
    sel = select(None, SimpleNamespace(label="base"), cands, None,
                  DiscrepancyOptions(max_effects=1), np.random.default_rng(0), soaks)
    return sel, asked


def test_a_drift_the_soak_confirms_names_what_a_spring_mimics(monkeypatch):
    tp = _drifting("thermal_preload", separable=False, drifts=True)
    sel, asked = _soak_run(monkeypatch, [[tp], []], {"thermal_preload": "drift"})
    assert sel.named == (tp,) and sel.withheld == () and asked == ["thermal_preload"]
    assert [t.outcome for t in sel.soak] == ["drift"]


@pytest.mark.parametrize("outcome, named", [("drift", "thermal_preload"),
                                             ("no_drift", "housing")])
def test_the_soak_splits_a_confounded_set(monkeypatch, outcome, named):
    tp = _drifting("thermal_preload", separable=True, drifts=True)
    hs = _drifting("housing", separable=True, drifts=False)
    sel, asked = _soak_run(monkeypatch, [[tp, hs], []], {"thermal_preload": outcome})
    assert [a.name for a in sel.named] == [named] and sel.confounded == ()
    assert asked == ["thermal_preload"]                 # only a drifting member is tested


def test_a_name_whose_drift_the_soak_rejects_is_withheld(monkeypatch):
    tp = _drifting("thermal_preload", separable=True, drifts=True)
    sel, _ = _soak_run(monkeypatch, [[tp]], {"thermal_preload": "no_drift"})
    assert sel.named == () and sel.withheld == (tp,)


def test_an_inconclusive_soak_or_none_changes_nothing(monkeypatch):
    tp = _drifting("thermal_preload", separable=False, drifts=True)
    sel, asked = _soak_run(monkeypatch, [[tp]], {"thermal_preload": "inconclusive"})
    assert sel.withheld == (tp,) and sel.named == () and len(sel.soak) == 1
    sel, asked = _soak_run(monkeypatch, [[tp]], {}, soaks=())
    assert sel.withheld == (tp,) and asked == [] and sel.soak == ()
    hs = _drifting("housing", separable=True, drifts=False)
    sel, asked = _soak_run(monkeypatch, [[hs], []], {})
    assert sel.named == (hs,) and asked == []           # nothing drifts: no test


def _soak_result(name: str, outcome: str) -> SoakTest:
    return SoakTest(name, outcome, 50.0, (12, 13), 1e-6 if outcome == "drift" else 0.5,
                    1.0 if outcome == "drift" else 0.0, 0.1, 3, 0.5, 1e-4, 0.1, 0.01, 4)


@pytest.mark.parametrize("outcome, says", [("drift", "confirms the drift"),
                                           ("no_drift", "rejects the drift"),
                                           ("inconclusive", "not separable from a generic")])
def test_a_withheld_groups_test_line_follows_the_soak(outcome, says):
    """A member the soak confirmed but a naming check failed, one whose drift it rejected, or
    an inconclusive soak (the encompassing test's line) — also for a member with a rival."""
    tp = _drifting("thermal_preload", separable=False, drifts=True)
    test = workflow._withheld_test((tp,), (_soak_result("thermal_preload", outcome),))
    assert says in test["kind"]
    assert ("soak" in test) is (outcome != "inconclusive")
    assert "mutual" in test or outcome != "inconclusive"
