"""The forward selection's control flow (``workflow._select``) with the stages stubbed: what a
group the encompassing test cannot separate from a generic change becomes under each
``generic_confound`` policy, and that the residual tests then run on the model carried."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy import workflow
from surrogate_rbrdo.discrepancy.naming import Assessment
from surrogate_rbrdo.discrepancy.rivals import RivalTest
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyOptions, _select

SPRING = "grounded spring at node 4 beside bearing front"


def _assessment(name: str, *, separable: bool, rival_adds: float = 0.1) -> Assessment:
    """A passing candidate whose closest rival is a spring: separable (the candidate adds
    20 > 6.63 to it) or not (0.5), the rival adding ``rival_adds`` to the candidate."""
    rt = RivalTest(20.0 if separable else 0.5, 6.63, SPRING, 30.0, rival_adds=rival_adds)
    fit = SimpleNamespace(fit=SimpleNamespace(label=f"fit of {name}"))
    return Assessment(name, 30.0, 1e-4, 1e-3, fit, {}, {"likelihood_ratio": True}, rt)


def _run(monkeypatch, groups, policy="unnamed_residual", max_effects=2):
    """``_select`` with ``decide`` answering ``groups`` stage by stage; returns the selection
    and the candidate names each stage was given."""
    given = []

    def run_stage(train, current, cands, ho, **kw):
        given.append((current, tuple(c.name for c in cands)))
        return SimpleNamespace(index=len(given) - 1)

    monkeypatch.setattr(workflow, "run_stage", run_stage)
    monkeypatch.setattr(workflow, "decide", lambda st, delta: list(groups[st.index]))
    cands = tuple(SimpleNamespace(name=n) for n in ("thermal_preload", "housing", "gyroscopics"))
    opts = DiscrepancyOptions(generic_confound=policy, max_effects=max_effects)
    base = SimpleNamespace(label="base")
    sel = _select(None, base, cands, None, opts, np.random.default_rng(0))
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
