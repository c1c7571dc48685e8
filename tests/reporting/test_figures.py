"""Figures: every one titled, axes with units, legends naming every labelled curve (or saying
"first N of M"), axis limits that show every plotted point."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo import (
    DesignModelOptions,
    OptimizationOptions,
    SubstructureOptions,
    campbell,
    fit_design_model,
    optimise,
    reference_problem,
    train_surrogate,
)
from surrogate_rbrdo.reporting.plots_spindle import plot_campbell
from surrogate_rbrdo.reporting.study import front_figures, spindle_figures

UNITLESS = {"generation"}


class Collect:
    """A stand-in run folder that keeps what is written."""

    def __init__(self):
        self.figures, self.tables = {}, {}

    def save_figure(self, name, fig):
        self.figures[name] = fig

    def write_csv(self, name, header, rows):
        self.tables[name] = (header, list(rows))


def check_figure(name, fig):
    titles = [ax.get_title() for ax in fig.axes] + [fig._suptitle.get_text()
                                                    if fig._suptitle else ""]
    assert any(t.strip() for t in titles), f"{name}: no title"
    for ax in fig.axes:
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            assert label, f"{name}: unlabelled axis"
            assert label in UNITLESS or "[" in label, f"{name}: no unit in {label!r}"
        x0, x1 = sorted(ax.get_xlim())
        y0, y1 = sorted(ax.get_ylim())
        for line in ax.get_lines():
            xy = np.column_stack([line.get_xdata(), line.get_ydata()]).astype(float)
            xy = xy[np.all(np.isfinite(xy), axis=1)]
            assert np.all((xy[:, 0] >= x0) & (xy[:, 0] <= x1)), f"{name}: x outside the axes"
            assert np.all((xy[:, 1] >= y0) & (xy[:, 1] <= y1)), f"{name}: y outside the axes"
        labelled = {h.get_label() for h in ax.get_lines() + ax.collections
                    if not h.get_label().startswith("_")}
        legends = [a.get_legend() for a in fig.axes] + list(fig.legends)
        shown = {t.get_text() for lg in legends if lg for t in lg.get_texts()}
        assert labelled <= shown, f"{name}: legend misses {labelled - shown}"


@pytest.fixture(scope="module")
def study_figures():
    p = reference_problem()
    r = [np.random.default_rng(s) for s in np.random.SeedSequence(4).spawn(3)]
    sur = train_surrogate(p.spindle, p.inputs, p.limit, SubstructureOptions(n_doe=14, n_jobs=1),
                          rng=r[0], response=p.response)
    dm = fit_design_model(p.spindle, DesignModelOptions(n_train=8, n_validate=0), rng=r[1])
    opts = OptimizationOptions(p_targets=(0.1, 0.05), strategies=("rdo", "rbdo"), n_theta=20,
                               pop_size=8, n_gen=3, n_jobs=1)
    opt = optimise(p, sur, dm, opts, crn=np.random.SeedSequence(5), rng=r[2])
    out = Collect()
    front_figures(out, opt, opts.weights, quantity=p.response.label, model_in_loop="surrogate",
                  baseline=p.baseline)
    spindle_figures(out, p.spindle, {"baseline": p.baseline}, n_speeds=30, campbell_speeds=4,
                    n_modes=3, limit_um=1.5)
    return out


@pytest.mark.parametrize("name", ["pareto_fronts.png", "pareto_fronts_with_rdo.png",
                                  "front_designs.png", "convergence.png", "campbell.png",
                                  "unbalance_response.png"])
def test_study_figures(study_figures, name):
    check_figure(name, study_figures.figures[name])


def test_convergence_names_its_objective(study_figures):
    ax = study_figures.figures["convergence.png"].axes[0]
    assert "μ_y" in ax.get_ylabel() and "objective 1, μ_y" in ax.get_title()


def test_campbell_says_first_n_of_m_and_shows_every_mode():
    sp = reference_problem().spindle
    camps = {k: campbell(sp.model(x), np.linspace(0.0, 24000.0, 4), n_modes=6)
             for k, x in (("a", sp.baseline), ("b", np.array([3000.0, 300.0, 80.0])))}
    fig = plot_campbell(camps, speed_max_rpm=24000.0, of_total=7)
    check_figure("campbell", fig)
    ax = fig.axes[0]
    assert "first 2 of 7 designs" in ax.get_title()
    top = max(np.nanmax(c.frequency_hz) for c in camps.values())
    assert ax.get_ylim()[1] >= top                  # the highest mode is inside the axes
