"""Running a study's samples as Dask tasks: on a local cluster of worker
processes, or on a scheduler given by its address; each finished task's row
is passed on as it arrives (a task that failed becomes an error row)."""

from __future__ import annotations

import os
import re

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


def _client(client, workers: int | None, n_tasks: int):
    """(client, things to close): the given client, one connected to an address, or
    a local cluster of ``workers`` processes."""
    dd = import_dask()
    if isinstance(client, str):
        check_address(client)
        try:
            c = dd.Client(client, timeout="20s")
        except (OSError, TimeoutError, ValueError, MemoryError) as exc:
            raise InputError(
                f"--scheduler {client}",
                f"cannot connect ({type(exc).__name__}: {exc})",
                "give the address of a running dask scheduler, such as tcp://host:8786",
            ) from None
        return c, [c]
    if client is not None:
        return client, []
    n = workers if workers is not None else os.cpu_count() or 1
    n = max(1, min(n, n_tasks))
    cluster = dd.LocalCluster(
        n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None
    )
    c = dd.Client(cluster)
    return c, [c, cluster]


def run_on_dask(plan, todo, on_row, client, workers) -> int:
    dd = import_dask()
    todo = list(todo)
    c, own = _client(client, workers, len(todo))
    n_workers = len(c.scheduler_info().get("workers", {}))
    futures = []
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
    finally:
        pending = [f for f in futures if not f.done()]
        if pending:
            c.cancel(pending)
        for thing in own:
            thing.close()
    return n_workers
