"""The virtual test rig and measured data (``docs/rig.md``, ``docs/measured-data.md``).

* the format and its files: :mod:`~.records`, :mod:`~.store`, :mod:`~.importers`, :mod:`~.checks`;
* the truth and its measurement: :mod:`~.truth`, :mod:`~.sensors`, :mod:`~.integrate`,
  :mod:`~.simulate`, :mod:`~.campaign`, :mod:`~.config`;
* signal processing: :mod:`~.demod` (1x, run-ups, critical speeds), :mod:`~.frf` (H1, modal
  fit); the phasor-domain fast path: :mod:`~.phasors`.
"""

from surrogate_rbrdo.rig.campaign import (
    CampaignOptions,
    CampaignResult,
    PhasorTable,
    read_phasors,
    run_campaign,
)
from surrogate_rbrdo.rig.checks import check_record
from surrogate_rbrdo.rig.demod import critical_speeds_from_ramp, demodulate, track_1x
from surrogate_rbrdo.rig.phasors import expected_phasors, sample_phasors
from surrogate_rbrdo.rig.records import (
    Calibration,
    ChannelSpec,
    Record,
    RecordError,
    SensorLocation,
)
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.rig.store import (
    Dataset,
    DatasetWriter,
    open_dataset,
    read_record,
    write_record,
)
from surrogate_rbrdo.rig.truth import (
    Truth,
    TruthState,
    Variability,
    reference_truth,
    spindle_truth,
)

__all__ = [
    "Calibration",
    "CampaignOptions",
    "CampaignResult",
    "ChannelSpec",
    "Dataset",
    "DatasetWriter",
    "PhasorTable",
    "Record",
    "RecordError",
    "SensorLocation",
    "SensorSet",
    "Truth",
    "TruthState",
    "Variability",
    "check_record",
    "critical_speeds_from_ramp",
    "demodulate",
    "expected_phasors",
    "open_dataset",
    "read_phasors",
    "read_record",
    "reference_truth",
    "spindle_truth",
    "run_campaign",
    "sample_phasors",
    "track_1x",
    "write_record",
]
