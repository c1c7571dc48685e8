"""Time every command the README documents and print a table to paste into it.

The commands are read from the README's ``## Experiments`` code block (every line starting
with ``rbrdo``) plus the test suite of the quick start, so a command added there is timed
without editing this script. Each runs in a fresh scratch folder (``experiments/`` linked in,
results and FE cache inside it, so every run starts cold and nothing is written into the
repository) with ``--no-progress``; ``rbrdo`` is ``python3 -m surrogate_rbrdo`` of this
checkout. Per command: wall time, CPU time and peak RSS of the process and its children
(``os.wait4``), and the 1-minute load average before and after — a figure measured at a load
above the machine's core count is inflated by the others' work and says so.

``--resume`` lines are timed by first starting the same run and interrupting it (SIGINT) after
``--interrupt-after`` seconds, then timing the resume.

Run on a quiet machine::

    python3 benchmarks/readme_timings.py                     # everything (about an hour quiet)
    python3 benchmarks/readme_timings.py --only quick spindle --skip paper
    python3 benchmarks/readme_timings.py --list              # the commands, not run
"""

from __future__ import annotations

import argparse
import os
import shlex
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: the quick start's test command (README, top)
EXTRA = ("python3 -m pytest -q",)


def readme_commands(readme: Path = ROOT / "README.md") -> list[str]:
    """The ``rbrdo ...`` lines of the README's ``## Experiments`` code block (comments cut)."""
    text = readme.read_text()
    section = text.split("## Experiments", 1)[1]
    block = section.split("```bash", 1)[1].split("```", 1)[0]
    out = []
    for line in block.splitlines():
        line = line.split("#", 1)[0].strip()
        if line.startswith("rbrdo"):
            out.append(" ".join(line.split()))
    return out + list(EXTRA)


def _argv(cmd: str) -> list[str]:
    words = shlex.split(cmd)
    if words[0] == "rbrdo":
        return [sys.executable, "-m", "surrogate_rbrdo", *words[1:]] + (
            ["--no-progress"] if words[1:2] == ["run"] else [])
    if words[:3] == ["python3", "-m", "pytest"]:
        return [sys.executable, *words[1:], "-p", "no:cacheprovider"]
    return words


def _run(argv: list[str], cwd: Path, env: dict[str, str], interrupt_after: float | None = None
         ) -> tuple[int, float, float, float]:
    """Exit code, wall s, CPU s (user + system, children included) and peak RSS MB."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, cwd=cwd, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, start_new_session=True)
    if interrupt_after is not None:
        try:
            proc.wait(timeout=interrupt_after)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGINT)
    _, status, ru = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    return proc.returncode, wall, ru.ru_utime + ru.ru_stime, ru.ru_maxrss / 1024.0


def _fmt(seconds: float) -> str:
    if seconds < 60:
        return f"{seconds:.1f} s"
    m, s = divmod(round(seconds), 60)
    return f"{m} min {s:02d} s"


def time_command(cmd: str, scratch: Path, interrupt_after: float) -> dict[str, object]:
    """Run one README command in ``scratch`` (the repository for the test suite)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg",
           **{v: "1" for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}}
    cwd = ROOT if "pytest" in cmd else scratch
    argv = _argv(cmd)
    if "--resume" in argv:      # make an interrupted run to resume first
        start = [a for a in argv if a != "--resume"]
        _run(start, cwd, env, interrupt_after=interrupt_after)
    load0 = os.getloadavg()[0]
    code, wall, cpu, rss = _run(argv, cwd, env)
    return {"command": cmd, "exit": code, "wall": wall, "cpu": cpu, "rss_mb": rss,
            "load": (load0, os.getloadavg()[0])}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="+", default=None,
                    help="time only commands containing one of these words")
    ap.add_argument("--skip", nargs="+", default=[],
                    help="skip commands containing one of these words (e.g. paper)")
    ap.add_argument("--list", action="store_true", help="print the commands, run nothing")
    ap.add_argument("--interrupt-after", type=float, default=60.0,
                    help="seconds before the run a --resume line continues is interrupted")
    args = ap.parse_args(argv)
    cmds = [c for c in readme_commands()
            if (args.only is None or any(w in c for w in args.only))
            and not any(w in c for w in args.skip)]
    if args.list:
        print("\n".join(cmds))
        return 0
    print(f"{len(cmds)} commands; {os.cpu_count()} cores; load now "
          f"{os.getloadavg()[0]:.1f}", flush=True)
    print("| command | wall time | CPU time | load average (1 min) | peak RSS | exit |")
    print("|---|---|---|---|---|---|", flush=True)
    with tempfile.TemporaryDirectory(prefix="readme_timings_") as tmp:
        scratch = Path(tmp)
        (scratch / "experiments").symlink_to(ROOT / "experiments")
        for cmd in cmds:
            r = time_command(cmd, scratch, args.interrupt_after)
            a, b = r["load"]
            print(f"| `{cmd}` | {_fmt(r['wall'])} | {_fmt(r['cpu'])} | {a:.1f} → {b:.1f} | "
                  f"{r['rss_mb']:.0f} MB | {r['exit']} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
