"""--overwrite keeps the finished run until the new one completes; a symbolic link is never
replaced; the FE cache is keyed to the code version (review item 14); --resume refuses a
changed input file (item 4)."""

from __future__ import annotations

import json
from importlib.resources import files

from surrogate_rbrdo.runner.experiments import spindle_report
from surrogate_rbrdo.sampling import fe as fe_module

from .test_runfolder import SPINDLE, _cfg, _meta, _run


def test_overwrite_keeps_the_old_run_until_the_new_one_completes(tmp_path, monkeypatch,
                                                                  capsys):
    cfg, res = _cfg(tmp_path, SPINDLE), tmp_path / "res"
    assert _run(cfg, res, "--run-id", "a") == 0
    old = (res / "t" / "a" / "summary.csv").read_bytes()

    def broken(*args, **kwargs):
        raise RuntimeError("the new run breaks")

    monkeypatch.setattr(spindle_report, "spindle_overview", broken)
    assert _run(cfg, res, "--run-id", "a", "--overwrite") == 1
    new = _meta(res / "t" / "a")
    assert new["status"] == "failed"
    aside = res / "t" / new["replaced_run"].rsplit("/", 1)[1]
    assert aside.is_dir() and _meta(aside)["status"] == "complete"      # nothing lost
    assert (aside / "summary.csv").read_bytes() == old
    monkeypatch.undo()
    assert _run(cfg, res, "--run-id", "a", "--overwrite") == 0       # completes: aside goes
    assert _meta(res / "t" / "a")["status"] == "complete"
    # both runs set aside (the finished one, the failed one) are gone
    assert sorted(p.name for p in (res / "t").iterdir() if p.name != "_fe_cache") == ["a"]
    capsys.readouterr()


def test_a_symlinked_run_folder_is_refused_not_removed(tmp_path, capsys):
    cfg, res = _cfg(tmp_path, SPINDLE), tmp_path / "res"
    assert _run(cfg, res, "--run-id", "a") == 0
    (res / "t" / "b").symlink_to(res / "t" / "a")
    capsys.readouterr()
    assert _run(cfg, res, "--run-id", "b", "--overwrite") == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is a symbolic link, not a run folder" in err
    assert (res / "t" / "b").is_symlink() and _meta(res / "t" / "a")["status"] == "complete"


def test_fe_cache_is_keyed_to_the_code_version(tmp_path, monkeypatch):
    monkeypatch.setattr(fe_module, "source_digest", lambda: "aaaa")
    old = fe_module.fe_cache(tmp_path).location
    monkeypatch.setattr(fe_module, "source_digest", lambda: "bbbb")
    new = fe_module.fe_cache(tmp_path).location
    assert old != new and old.endswith("code-aaaa") and new.endswith("code-bbbb")
    assert json.dumps(str(tmp_path)) and str(tmp_path) in old


def test_resume_refuses_a_changed_input_file(tmp_path, monkeypatch, capsys):
    """Review item 4: a geometry file changed between the start and --resume."""
    geo = tmp_path / "g.toml"
    ref = (files("surrogate_rbrdo") / "data" / "reference_spindle.toml").read_text()
    assert ref.count("mass_kg = 1.8") == 1 and ref.count("magnitude_kgm = 0.0") == 2
    ref = ref.replace("magnitude_kgm = 0.0", "magnitude_kgm = 1e-5")   # the file's own
    geo.write_text(ref)
    cfg = _cfg(tmp_path, SPINDLE.replace('kind = "spindle_report"',
                                         'kind = "spindle_report"\n[spindle]\ngeometry = "g.toml"'))
    res = tmp_path / "res"

    def broken(*args, **kwargs):
        raise RuntimeError("stop here")

    monkeypatch.setattr(spindle_report, "spindle_overview", broken)
    assert _run(cfg, res, "--run-id", "r") == 1
    monkeypatch.undo()
    geo.write_text(ref.replace("mass_kg = 1.8", "mass_kg = 3.6"))   # the review's change
    capsys.readouterr()
    assert _run(cfg, res, "--run-id", "r", "--resume") == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "g.toml" in err and "changed since" in err
    assert _run(cfg, res, "--run-id", "r", "--resume", "--accept-changes") == 0
    assert _meta(res / "t" / "r")["accepted_changes"]
