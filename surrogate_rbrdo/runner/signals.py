"""Ctrl-C and SIGTERM for the ``rbrdo`` process, and no orphaned worker processes.

* SIGTERM raises :class:`~surrogate_rbrdo.runner.execute.Terminated` in the main thread (the
  run is marked ``interrupted`` and the stack unwinds).
* Ctrl-C sends SIGINT to the terminal's whole process group, joblib's loky workers included;
  a worker starting up or computing would die printing a traceback. So SIGINT is *blocked*
  in every thread of this process (threads and child processes inherit the mask, so the
  workers never see it) and one relay thread waits for it with ``sigwait`` and interrupts the
  main thread (``KeyboardInterrupt``), waking it with SIGUSR1 if it waits in a lock.
* :func:`stop_workers` kills loky's reusable workers (idle ones otherwise live 300 s, and an
  interrupted run must not leave them computing).
"""

from __future__ import annotations

import _thread
import multiprocessing.resource_tracker
import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from joblib.externals.loky import reusable_executor

from surrogate_rbrdo.runner.execute import Terminated


def stop_workers(kill: bool = True) -> None:
    """Stop joblib's reusable loky worker processes, if any: killed (``kill``, after an
    interruption: they may be computing) or asked to exit (they then release what they hold,
    e.g. tqdm's semaphores, which a killed worker leaks)."""
    executor = reusable_executor._executor   # joblib keeps its one executor here
    if executor is not None:
        executor.shutdown(wait=True, kill_workers=kill)


def _terminate(signum: int, frame: Any) -> None:
    raise Terminated()


def _relay(main_ident: int, stop: threading.Event) -> None:
    # a short poll: leaving ``handled_signals`` joins this thread, so every ``rbrdo run``
    # (and every test of the CLI) waits up to one poll on exit
    while not stop.is_set():
        if signal.sigtimedwait({signal.SIGINT}, 0.02) is not None:
            _thread.interrupt_main(signal.SIGINT)
            signal.pthread_kill(main_ident, signal.SIGUSR1)   # wake a blocking wait


@contextmanager
def handled_signals() -> Iterator[None]:
    """Inside: SIGTERM raises ``Terminated``, Ctrl-C raises ``KeyboardInterrupt`` in the main
    thread only; on exit the worker processes are stopped and the handlers restored."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old: dict[int, Callable[..., Any] | int | None] = {
        signal.SIGTERM: signal.signal(signal.SIGTERM, _terminate),
        signal.SIGUSR1: signal.signal(signal.SIGUSR1, lambda *_: None)}
    # CPython 3.11's resource tracker, started on first use, unblocks SIGINT and SIGTERM in
    # the thread that starts it (it does not restore the mask): start it now, unblocked
    multiprocessing.resource_tracker.ensure_running()
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    stop = threading.Event()
    relay = threading.Thread(target=_relay, args=(threading.get_ident(), stop), daemon=True,
                             name="rbrdo-sigint-relay")
    relay.start()
    ok = False
    try:
        yield
        ok = True
    finally:
        stop.set()
        relay.join()
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
        for sig, handler in old.items():
            signal.signal(sig, handler)
        stop_workers(kill=not ok)


__all__ = ["handled_signals", "stop_workers"]
