"""Figures: every one titled, its title and legend inside the figure, axes with units, legends
naming every labelled curve and scatter (or saying "first N of M"), axis limits that show every
plotted point (lines and scatter collections) — for the study's figures and for every figure
the ``spindle_report`` and ``surrogate_validation`` kinds write."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PathCollection

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
from surrogate_rbrdo.runner.execute import run_experiment
from surrogate_rbrdo.runner.runfolder import RunFolder

UNITLESS = {"generation"}


class Collect:
    """A stand-in run folder that keeps what is written."""

    def __init__(self):
        self.figures, self.tables = {}, {}

    def save_figure(self, name, fig):
        self.figures[name] = fig

    def write_csv(self, name, header, rows):
        self.tables[name] = (header, list(rows))


def check_inside(name, fig):
    """Titles (axes and figure) and legends lie inside the figure, after layout."""
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    r, W, H = canvas.get_renderer(), fig.bbox.width, fig.bbox.height
    texts = [t for ax in fig.axes for t in (ax.title, ax._left_title, ax._right_title)]
    texts += [fig._suptitle] if fig._suptitle else []
    boxes = [(f"title {t.get_text()!r}", t.get_window_extent(r)) for t in texts
             if t.get_text()]
    legends = [a.get_legend() for a in fig.axes] + list(fig.legends)
    boxes += [("legend", lg.get_window_extent(r)) for lg in legends if lg]
    for what, bb in boxes:
        assert bb.x0 >= -1 and bb.y0 >= -1 and bb.x1 <= W + 1 and bb.y1 <= H + 1, \
            f"{name}: {what} is cut off ({bb.bounds} in {W} x {H})"


def _inside(name, xy, ax):
    x0, x1 = sorted(ax.get_xlim())
    y0, y1 = sorted(ax.get_ylim())
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    assert np.all((xy[:, 0] >= x0) & (xy[:, 0] <= x1)), f"{name}: x outside the axes"
    assert np.all((xy[:, 1] >= y0) & (xy[:, 1] <= y1)), f"{name}: y outside the axes"


def check_figure(name, fig):
    titles = [ax.get_title() for ax in fig.axes] + [fig._suptitle.get_text()
                                                    if fig._suptitle else ""]
    assert any(t.strip() for t in titles), f"{name}: no title"
    check_inside(name, fig)
    for ax in fig.axes:
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            assert label, f"{name}: unlabelled axis"
            assert label in UNITLESS or "[" in label, f"{name}: no unit in {label!r}"
        for line in ax.get_lines():
            _inside(name, np.column_stack([line.get_xdata(), line.get_ydata()]), ax)
        for coll in ax.collections:            # scatter points, in data coordinates
            if isinstance(coll, PathCollection) and coll.get_offset_transform() is ax.transData:
                _inside(name, coll.get_offsets(), ax)
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


SPINDLE_REPORT = """[experiment]
name = "figs"
kind = "spindle_report"
[report]
designs = { "a (stiff)" = [3000.0, 300.0, 80.0], b = [1000.0, 750.0, 50.0] }
include_box = true
n_speeds = 30
campbell_speeds = 4
n_modes = 4
n_campbell = 3
"""

VALIDATION = """[experiment]
name = "figs"
kind = "surrogate_validation"
seed = 3
[surrogate]
n_doe = 14
n_jobs = 1
n_start = 1
[validation]
n_test = 8
n_theta = 20
n_theta_nc = 4
designs = { near = [2000.0, 460.0, 65.0] }
[validation.variants.resonance-with-a-long-name]
structure = "resonance"
n_doe = 16
"""


@pytest.fixture(scope="module")
def kind_figures(tmp_path_factory):
    """Every figure the spindle_report and surrogate_validation kinds save, by kind/name."""
    tmp = tmp_path_factory.mktemp("figs")
    seen = {}
    real = RunFolder.save_figure

    def keep(self, name, fig):
        seen[f"{self.path.parent.parent.name}-{self.run_id}/{name}"] = fig
        return real(self, name, fig)

    RunFolder.save_figure = keep
    try:
        for kind, text in (("spindle_report", SPINDLE_REPORT), ("validation", VALIDATION)):
            cfg = tmp / f"{kind}.toml"
            cfg.write_text(text)
            run_experiment(cfg, results_dir=tmp / "res", run_id=kind, progress=False)
    finally:
        RunFolder.save_figure = real
    return seen


def test_every_figure_of_the_kinds_is_checked(kind_figures):
    names = sorted(kind_figures)
    assert names == sorted([
        "res-spindle_report/campbell.png", "res-spindle_report/unbalance_response.png",
        "res-validation/parity_main.png", "res-validation/parity_log_main.png",
        "res-validation/parity_resonance-with-a-long-name.png",
        "res-validation/parity_log_resonance-with-a-long-name.png"]), names
    for name, fig in kind_figures.items():
        check_figure(name, fig)


def test_campbell_of_a_report_says_first_n_of_m(kind_figures):
    ax = kind_figures["res-spindle_report/campbell.png"].axes[0]
    assert "first 3 of 11 designs" in ax.get_title()          # 2 given + 8 corners + centre


def test_a_cut_off_title_and_a_point_outside_are_caught():
    """The checks can fail: a title wider than its figure, a scatter point outside the
    limits."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(3, 3))
    ax = fig.subplots()
    ax.set_title("a title much too long for a figure of three inches, which is cut off")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    with pytest.raises(AssertionError, match="is cut off"):
        check_figure("long", fig)
    fig = Figure(figsize=(4, 4), layout="constrained")
    ax = fig.subplots()
    ax.scatter([0.0, 10.0], [0.0, 10.0], label="points")
    ax.set_xlim(0, 5)
    ax.set_title("t")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend()
    with pytest.raises(AssertionError, match="x outside the axes"):
        check_figure("scatter", fig)
