"""What the experiment kind ``discrepancy`` composes: the ``[discrepancy]`` table → options, a
measured-data folder → observables, and the analysis → a frozen result and its files.

The kind (``surrogate_rbrdo/runner/experiments/discrepancy.py``, ``rbrdo run
experiments/discrepancy.toml``) does, in order:

1. the model: ``build_spindle([spindle])`` → its geometry at the baseline design and its effects;
2. the data: with ``[rig]``, the virtual rig's campaign into ``<run>/campaign``
   (``rig.campaign.run_campaign``); with ``[data] path`` a finished rig run folder, a folder
   with ``phasors.csv`` or a dataset folder (``docs/measured-data.md``); either way
   :func:`data_from_folder`;
3. :func:`analyse` with :class:`DiscrepancyTable` ``.options()`` and the experiment's seed;
4. the figures: ``reporting.plots_discrepancy.plot_all(result, <run>)``.

``[discrepancy]`` is checked by :func:`~surrogate_rbrdo.core.schema.parse` against
:class:`DiscrepancyTable` (strict types, unknown keys refused, errors name the dotted field):

>>> o = options_from_dict({"alpha": 0.01, "nuisance": {"preset": "probe_chain"}})
>>> o.nuisance.gain_sd, o.alpha
(0.02, 0.01)
>>> options_from_dict({"alpha": 0.5})
Traceback (most recent call last):
...
ValueError: discrepancy.alpha = 0.5 is not allowed: must lie in [1e-06, 0.2]
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.core.validate import check_choice
from surrogate_rbrdo.discrepancy.measured import (
    channel_positions,
    dataset_phasor_rows,
    impact_data,
    phasor_block,
    read_phasor_table,
    soak_blocks,
)
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions
from surrogate_rbrdo.discrepancy.observables import THIN_IMPACTS, MeasuredData
from surrogate_rbrdo.discrepancy.report import write_run
from surrogate_rbrdo.discrepancy.workflow import (
    DiscrepancyOptions,
    DiscrepancyResult,
    find_discrepancy,
)
from surrogate_rbrdo.spindle.effects import Effect
from surrogate_rbrdo.spindle.geometry import SpindleGeometry

#: nuisance presets: the probe chain of docs/rig.md, or an ideal chain
PRESETS = {"probe_chain": NuisanceOptions.probe_chain, "ideal": NuisanceOptions}


@dataclass(frozen=True)
class NuisanceTable:
    """``[discrepancy.nuisance]``: a ``preset`` (``"probe_chain"``: the rig's eddy-current
    chain, :meth:`~.nuisance.NuisanceOptions.probe_chain`; ``"ideal"``: the
    :class:`~.nuisance.NuisanceOptions` defaults) and any of its fields, which override it."""

    preset: str = "ideal"
    theta_bounds: tuple[float, float] | None = None
    damping: str | None = None
    damping_bounds: tuple[float, float] | None = None
    mass_disks: tuple[str, ...] | None = None
    mass_sd: float | None = None
    gain_sd: float | None = None
    bandwidth_hz: float | None = None
    delay_sd_s: float | None = None
    force_gain_sd: float | None = None
    force_delay_sd_s: float | None = None
    impact_theta_sd: float | None = None

    def __post_init__(self) -> None:
        check_choice("preset", self.preset, PRESETS)
        self.options()

    def options(self) -> NuisanceOptions:
        """The preset with the given fields replaced."""
        given = {f.name: getattr(self, f.name) for f in fields(self)
                 if f.name != "preset" and getattr(self, f.name) is not None}
        try:
            return PRESETS[self.preset](**given)
        except ValueError as exc:       # "nuisance.mass_sd = ..." -> "mass_sd = ..."
            raise ValueError(str(exc).removeprefix("nuisance.")) from None


_D = DiscrepancyOptions       # the class: its attributes are the fields' defaults


@dataclass(frozen=True)
class DiscrepancyTable:
    """``[discrepancy]``: the fields of :class:`~.workflow.DiscrepancyOptions` (same defaults
    and checks) with ``nuisance`` a :class:`NuisanceTable`."""

    # the defaults are the workflow's own (one source: DiscrepancyOptions)
    library: tuple[str, ...] = _D.library
    nuisance: NuisanceTable = field(default_factory=NuisanceTable)
    alpha: float = _D.alpha
    alpha_residual: float = _D.alpha_residual
    n_draws: int = _D.n_draws
    holdout_every: int = _D.holdout_every
    extrapolate_fraction: float = _D.extrapolate_fraction
    max_effects: int = _D.max_effects
    confound_delta: float = _D.confound_delta
    holdout_tolerance: float = _D.holdout_tolerance
    use_identified: bool = _D.use_identified
    use_impacts: bool = _D.use_impacts
    min_impact_dof: int = _D.min_impact_dof
    max_nfev: int = _D.max_nfev
    n_jobs: int = _D.n_jobs
    generic_confound: str = _D.generic_confound

    def __post_init__(self) -> None:
        self.options()

    def options(self) -> DiscrepancyOptions:
        """The workflow's options (its ``__post_init__`` checks every field)."""
        kw = {f.name: getattr(self, f.name) for f in fields(self)}
        return DiscrepancyOptions(**{**kw, "nuisance": self.nuisance.options()})


def options_from_dict(table: Mapping[str, Any]) -> DiscrepancyOptions:
    """``[discrepancy]`` → :class:`~.workflow.DiscrepancyOptions` (through
    :class:`DiscrepancyTable`; errors name ``discrepancy.<field>``)."""
    return parse(DiscrepancyTable, table, "discrepancy").options()


def data_files(path: str | Path) -> tuple[Path, ...]:
    """The files :func:`data_from_folder` reads from ``path`` (for provenance: their hashes
    let a resumed run refuse changed data): ``phasors.csv`` and ``channels.json`` or the
    first native record; for a dataset folder every file under it.

    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = (d / "phasors.csv").write_text("x"); _ = (d / "channels.json").write_text("{}")
    >>> [p.name for p in data_files(d)]
    ['phasors.csv', 'channels.json']
    """
    root = Path(path)
    table = root / "phasors.csv"
    if not table.is_file():
        return tuple(sorted(p for p in root.rglob("*") if p.is_file()))
    sidecar = root / "channels.json"
    if sidecar.is_file():
        return table, sidecar
    return (table,) + tuple(sorted((root / "dataset" / "records").glob("*.npz"))[:1])


def data_from_folder(path: str | Path, *, impacts: bool = True) -> MeasuredData:
    """Observables from a measured-data folder: ``phasors.csv`` (the rig campaign's 1x table,
    or a user's in the same columns) and the channels' positions from ``channels.json``
    (``{name: [position_mm, direction]}``) or else from the first native record of
    ``dataset/records``; or a dataset folder of ``docs/measured-data.md`` (``dataset.json``,
    ``index.jsonl``, ``records/``), whose steady records are demodulated
    (:func:`~.measured.dataset_phasor_rows`). With ``impacts`` (default, as
    ``DiscrepancyOptions.use_impacts``), the impact records of the
    dataset (a rig campaign's ``dataset/``, or the dataset folder itself) become FRF blocks,
    one per speed and hit direction (:func:`~.measured.impact_blocks`); those with too few
    hits are listed in the provenance (:data:`~.observables.THIN_IMPACTS`). The dataset's
    soak records become ``MeasuredData.soaks`` (:func:`~.measured.soak_blocks`; none
    without)."""
    root = Path(path)
    if not root.is_dir():
        raise ValueError(f"data folder {str(root)!r} is not allowed: it is not a folder")
    table = root / "phasors.csv"
    if not table.is_file() and (root / "index.jsonl").is_file():
        rows, pos = dataset_phasor_rows(root)
        imp, thin = impact_data(root) if impacts else ((), ())
        return MeasuredData((phasor_block(rows, pos),) + imp,
                            provenance=_provenance(root, thin), soaks=soak_blocks(root))
    if not table.is_file():
        raise ValueError(f"data folder {str(root)!r}: no phasors.csv (the 1x phasor table) "
                         "and no index.jsonl (a dataset folder)")
    sidecar = root / "channels.json"
    if sidecar.is_file():
        pos = {k: (float(v[0]), str(v[1])) for k, v in json.loads(sidecar.read_text()).items()}
    else:
        recs = sorted((root / "dataset" / "records").glob("*.npz"))
        if not recs:
            raise ValueError(f"data folder {str(root)!r}: neither channels.json nor "
                             "dataset/records/*.npz to read the channels' positions from")
        pos = channel_positions(recs[0])
    ds = root / "dataset"
    has_ds = (ds / "index.jsonl").is_file()
    imp, thin = impact_data(ds) if impacts and has_ds else ((), ())
    return MeasuredData((phasor_block(read_phasor_table(table), pos),) + imp,
                        provenance=_provenance(root, thin),
                        soaks=soak_blocks(ds) if has_ds else ())


def _provenance(root: Path, thin: tuple[tuple[str, int], ...]) -> dict:
    """The data's source and the impact blocks the reader left out (too few hits)."""
    return {"source": str(root), **({THIN_IMPACTS: list(thin)} if thin else {})}


def analyse(data: MeasuredData, geometry: SpindleGeometry, effects: tuple[Effect, ...], *,
            spindle_section: Mapping[str, Any], options: DiscrepancyOptions,
            rng: np.random.Generator, out_dir: str | Path
            ) -> tuple[DiscrepancyResult, dict[str, Path]]:
    """Run the workflow and write its files (``findings.json``, ``spindle_updated.toml``,
    ``candidates.csv``, ``curves.csv``) into ``out_dir``."""
    rng = require_rng(rng)
    result = find_discrepancy(data, geometry, effects, options=options, rng=rng)
    paths = write_run(result, out_dir, spindle_section=spindle_section, model_effects=effects)
    return result, paths
