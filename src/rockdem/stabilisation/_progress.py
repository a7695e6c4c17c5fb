"""Progress notes of a stabilisation study: what is being computed, as one line.

A study runs many factor-of-safety searches and staged analyses (half a
minute and more); :func:`reporting` lets a caller (the ``stabilise``
command's progress line) receive a short note at each of them without
threading a callback through every function.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar

_sink: ContextVar[Callable[[str], None] | None] = ContextVar("rockdem_stab_sink", default=None)
_stage: ContextVar[str] = ContextVar("rockdem_stab_stage", default="")


def note(text: str) -> None:
    """Send ``text`` (prefixed with the current stage) to the listener, if any."""
    sink = _sink.get()
    if sink is not None:
        stage = _stage.get()
        sink(f"{stage}: {text}" if stage and text else stage or text)


@contextmanager
def reporting(callback: Callable[[str], None] | None) -> Iterator[None]:
    """Send the notes made inside the block to ``callback`` (None: nowhere)."""
    token = _sink.set(callback)
    try:
        yield
    finally:
        _sink.reset(token)


@contextmanager
def stage(label: str) -> Iterator[None]:
    """Name what the notes inside the block belong to, and say it has started."""
    token = _stage.set(label)
    try:
        note("")
        yield
    finally:
        _stage.reset(token)


def trial_hook() -> Callable | None:
    """A ``progress`` hook for :func:`rockdem.factor_of_safety` that notes each
    trial factor (None when nobody listens)."""
    if _sink.get() is None:
        return None

    def hook(trial) -> None:
        verdict = "stable" if trial.stable else "no equilibrium"
        note(f"strength trial F = {trial.factor:.4f}, {verdict}")

    return hook
