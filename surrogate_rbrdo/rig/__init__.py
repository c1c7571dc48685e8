"""The virtual test rig and measured data.

* :mod:`~surrogate_rbrdo.rig.records`: the measured-data format (:class:`Record`, channels,
  calibration, provenance) that the rig writes and a user's data is put into;
* :mod:`~surrogate_rbrdo.rig.store`: records and datasets on disk (streaming, resumable).

See ``docs/measured-data.md`` and ``docs/rig.md``.
"""

from surrogate_rbrdo.rig.records import (
    Calibration,
    ChannelSpec,
    Record,
    RecordError,
    SensorLocation,
)
from surrogate_rbrdo.rig.store import (
    Dataset,
    DatasetWriter,
    open_dataset,
    read_record,
    write_record,
)

__all__ = [
    "Calibration",
    "ChannelSpec",
    "Dataset",
    "DatasetWriter",
    "Record",
    "RecordError",
    "SensorLocation",
    "open_dataset",
    "read_record",
    "write_record",
]
