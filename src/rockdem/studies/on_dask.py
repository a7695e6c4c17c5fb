"""Running a study's samples as Dask tasks: on a local cluster of worker
processes, or on a scheduler given by its address; each finished task's row
is passed on as it arrives (a task that failed becomes an error row)."""

from __future__ import annotations

import logging
import os
import re
import signal
import threading
from contextlib import contextmanager, nullcontext

from ..errors import InputError
from .run import INSTALL_HINT, _args, _error_row, evaluate


def import_dask():
    """``dask.distributed``, or an InputError saying how to install it."""
    try:
        import dask.distributed as dd
    except ImportError:
        raise InputError(
            "rockdem study", "needs dask[distributed], pandas and pyarrow", INSTALL_HINT
        ) from None
    return dd


def check_address(client: str) -> None:
    if not re.fullmatch(r"(tcp|tls|ucx|ws|wss)://[^\s/:]+:\d{1,5}/?", client):
        raise InputError(
            f"--scheduler {client}",
            "is not a dask scheduler address",
            "give one such as tcp://host:8786",
        )


#: Seconds a scheduler given by its address has to answer.
CONNECT_TIMEOUT = 20


def connect(address: str):
    """A client of the dask scheduler at ``address``, or an InputError in one line
    naming the address and the fix.  :func:`rockdem.study` calls it before it
    writes anything, so that a scheduler that cannot be reached leaves the
    results folder as it was.

    The underlying error is not quoted: dask reads whatever answers at the
    address as its own messages, and a web server there gave "MemoryError:
    Unable to allocate 3.07 EiB" (found by fuzzing)."""
    dd = import_dask()
    check_address(address)
    try:
        return dd.Client(address, timeout=f"{CONNECT_TIMEOUT}s")
    except Exception as exc:
        if isinstance(exc, TimeoutError) or "timed out" in str(exc).lower():
            problem = f"no dask scheduler answered there within {CONNECT_TIMEOUT:g} s"
        elif isinstance(exc, OSError):
            problem = f"no dask scheduler answered there ({exc.strerror or 'unreachable'})"
        else:  # something answered, but not in dask's protocol
            problem = "what answers there is not a dask scheduler (or not a compatible one)"
        raise InputError(
            f"--scheduler {address}",
            problem,
            "start one (`dask scheduler`) and give its address, such as tcp://host:8786",
        ) from None


@contextmanager
def _workers_ignore_ctrl_c():
    """Start the local workers with Ctrl-C ignored (inherited by the processes
    they spawn): Ctrl-C reaches the whole process group, and each worker
    printed a KeyboardInterrupt traceback of 20-30 lines after the study's
    "interrupted" (found by hostile testing).  The study stops them itself."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def _client(client, workers: int | None, n_tasks: int):
    """(client, things to close): the given client, one connected to an address, or
    a local cluster of ``workers`` processes."""
    dd = import_dask()
    if isinstance(client, str):
        c = connect(client)
        return c, [c]
    if client is not None:
        return client, []
    n = workers if workers is not None else os.cpu_count() or 1
    n = max(1, min(n, n_tasks))
    with _workers_ignore_ctrl_c():
        cluster = dd.LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None
        )
    c = dd.Client(cluster)
    return c, [c, cluster]


def _quiet_worker() -> None:
    logging.getLogger("distributed").setLevel(logging.CRITICAL + 1)


@contextmanager
def _quiet(c):
    """No logging from our own cluster while it is torn down after Ctrl-C:
    its workers logged a warning of 3 lines per cancelled task, and its
    scheduler (in this process) pages of CRITICAL tracebacks about the
    client it could no longer tell, after the study's "interrupted".  Nor
    from tornado, whose event loop logs the tracebacks of callbacks that
    distributed left behind when Ctrl-C cut one of its calls short (a
    NameError in ``distributed.utils.sync``'s ``cancel``, seen once in a
    fresh install's test run).  Quiet here first: tearing down logs too."""
    here = [logging.getLogger(name) for name in ("distributed", "tornado", "asyncio")]
    levels = [log.level for log in here]
    for log in here:
        log.setLevel(logging.CRITICAL + 1)
    try:
        c.run(_quiet_worker, wait=True)
    except Exception:  # the study stops either way
        pass
    try:
        yield
    finally:
        for log, level in zip(here, levels, strict=True):
            log.setLevel(level)


class _SyncCancelFilter(logging.Filter):
    """Drop the traceback tornado logs for distributed's own ``sync`` cancel
    callback failing after Ctrl-C (``NameError: cannot access free variable
    'future'`` in ``distributed/utils.py``): it runs on the event loop's
    thread as the interrupt reaches the study, before the study can quiet
    anything, and printed 8 lines before "interrupted" (a fresh install's
    test run; the race is rare)."""

    def filter(self, record: logging.LogRecord) -> bool:
        tb = record.exc_info[2] if record.exc_info else None
        while tb is not None and tb.tb_next is not None:
            tb = tb.tb_next
        if tb is None:
            return True
        code = tb.tb_frame.f_code
        return not (
            code.co_name == "cancel"
            and code.co_filename.endswith("utils.py")
            and "distributed" in code.co_filename
        )


#: installed for the rest of the process by the first study on Dask: the
#: callback may run after the study has returned, while "interrupted" is printed
_CANCEL_FILTER = _SyncCancelFilter()


def run_on_dask(plan, todo, on_row, client, workers) -> int:
    logging.getLogger("tornado.application").addFilter(_CANCEL_FILTER)  # (once)
    dd = import_dask()
    todo = list(todo)
    c, own = _client(client, workers, len(todo))
    n_workers = len(c.scheduler_info().get("workers", {}))
    futures = []
    interrupted = False
    try:
        [base] = c.scatter([plan.base], broadcast=True)
        futures = [c.submit(evaluate, *_args(plan, i, base), pure=False, retries=0) for i in todo]
        sample_of = {f.key: i for f, i in zip(futures, todo, strict=True)}
        for fut in dd.as_completed(futures):
            if fut.status == "finished":
                row = fut.result()
            else:
                exc = fut.exception() if fut.status == "error" else fut.status
                row = _error_row(plan, sample_of[fut.key], f"task {fut.status}: {exc}")
            fut.release()
            on_row(row)
    except KeyboardInterrupt:
        interrupted = True
        raise
    finally:
        if interrupted and own:
            global OWN_CLUSTER_INTERRUPTED
            OWN_CLUSTER_INTERRUPTED = True
            _within(TEARDOWN_SECONDS, _tear_down, c, futures, own)
        else:
            _tear_down(c, futures, own, quiet=False)
    return n_workers


#: set when Ctrl-C stopped a study on its own local cluster: the command
#: line then ends the process without the interpreter's exit handlers
#: (rockdem.cli.main), where distributed's would close that cluster again
OWN_CLUSTER_INTERRUPTED = False

#: Seconds the study waits, after Ctrl-C, for its own cluster to close; the
#: worker processes exit with this process if it has not (distributed's
#: workers watch their parent).
TEARDOWN_SECONDS = 15.0


def _tear_down(c, futures, own, quiet: bool = True) -> None:
    """Cancel what is still pending and close the client and cluster we own."""
    with _quiet(c) if quiet else nullcontext():
        pending = [f for f in futures if not f.done()]
        if pending:
            c.cancel(pending)
        for thing in own:
            thing.close()


def _within(seconds: float, fn, *args) -> bool:
    """Run ``fn(*args)`` on a daemon thread and wait at most ``seconds``: after
    Ctrl-C the user waits for "interrupted", not for a cluster's graceful close
    (the test of it timed out after 60 s in two full-suite runs, where the
    client's own close timeout is 60 s).  True if it finished in time."""
    done = threading.Event()

    def run() -> None:
        try:
            fn(*args)
        except Exception:  # the study stops either way
            pass
        finally:
            done.set()

    threading.Thread(target=run, name="rockdem-teardown", daemon=True).start()
    return done.wait(seconds)
