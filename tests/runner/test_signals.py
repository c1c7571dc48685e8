"""SIGTERM and Ctrl-C of a real ``rbrdo run`` with loky worker processes: one line on stderr,
exit 143 / 130, the run marked ``interrupted``, and no process of its session left behind
(found by scanning /proc for the session id after the parent exited)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")

SLOW = """
[experiment]
name = "slow"
kind = "study"
seed = 1
[surrogate]
n_doe = 300
n_jobs = 2
n_start = 1
[optimization]
n_theta = 40
pop_size = 8
n_gen = 4
"""


def _session(sid: int) -> list[tuple[int, str]]:
    """Live (not zombie) processes of session ``sid``: (pid, command line)."""
    out = []
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            st = Path(f"/proc/{d}/stat").read_text()
            cmd = Path(f"/proc/{d}/cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        fields = st[st.rindex(")") + 2:].split()
        if int(fields[3]) == sid and fields[0] != "Z":
            out.append((int(d), cmd))
    return out


def _default_sigint() -> None:
    """A terminal's Ctrl-C reaches a process that has SIGINT at its default; a test suite run
    in the background (``cmd &``, ``nohup``) has it ignored, and children inherit that."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start_and_signal(tmp_path: Path, sig: int, group: bool) -> tuple[subprocess.Popen, str]:
    cfg = tmp_path / "slow.toml"
    cfg.write_text(SLOW)
    p = subprocess.Popen(
        [sys.executable, "-m", "surrogate_rbrdo", "run", str(cfg), "--results",
         str(tmp_path / "res"), "--run-id", "s", "--no-progress"],
        env=dict(os.environ), start_new_session=True, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint)
    t0 = time.monotonic()
    while time.monotonic() - t0 < 120:          # until two loky workers compute
        if sum("loky" in c for _, c in _session(p.pid)) >= 2:
            break
        if p.poll() is not None:
            pytest.fail(f"rbrdo exited early: {p.communicate()}")
        time.sleep(0.1)
    else:
        pytest.fail("no loky worker started within 120 s")
    time.sleep(0.5)
    (os.killpg if group else os.kill)(p.pid, sig)
    _, err = p.communicate(timeout=120)
    return p, err


def _no_orphans(sid: int) -> None:
    for _ in range(100):
        left = _session(sid)
        if not left:
            return
        time.sleep(0.1)
    pytest.fail(f"processes of the run still alive 10 s after it exited: {left}")


def test_sigterm_stops_the_workers_and_marks_the_run(tmp_path):
    p, err = _start_and_signal(tmp_path, signal.SIGTERM, group=False)
    assert p.returncode == 143, err
    assert err.count("\n") == 1 and err.startswith("rbrdo: terminated (SIGTERM)"), err
    _no_orphans(p.pid)
    meta = json.loads((tmp_path / "res" / "slow" / "s" / "meta.json").read_text())
    assert meta["status"] == "interrupted" and meta["signal"] == "SIGTERM"


def test_ctrl_c_prints_one_line_and_exits_130(tmp_path):
    """Ctrl-C in a terminal signals the whole process group, the workers included."""
    p, err = _start_and_signal(tmp_path, signal.SIGINT, group=True)
    assert p.returncode == 130, err
    assert err.count("\n") == 1 and err.startswith("rbrdo: interrupted (Ctrl-C)"), err
    assert "--resume --run-id s" in err
    _no_orphans(p.pid)
    meta = json.loads((tmp_path / "res" / "slow" / "s" / "meta.json").read_text())
    assert meta["status"] == "interrupted" and meta["signal"] == "SIGINT"
