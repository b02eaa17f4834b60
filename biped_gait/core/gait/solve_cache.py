"""Solves kept on disk: the double support that lasts and the actuated swing (IPOPT, tens of seconds
each) answered again at once when the same code solves the same program for the same ends.

joblib's ``Memory`` keeps each result under a hash of its key: the kind of solve, this package's
``core`` code (any change to it is another key), the parameter set, the gait's ends as the
program sees them (the touchdown posture, the velocities before and after, the period: their
exact bytes, so a gait planned otherwise on another machine is another key), the flow's steps
and kind, the friction, and the request. The directory is ``$BIPED_GAIT_CACHE`` if set, else
``$XDG_CACHE_HOME/biped_gait`` (``~/.cache`` by default); ``BIPED_GAIT_CACHE=off`` solves every
time. A key being solved is solved once: the processes that ask for it meanwhile wait for that
solve. Removing the directory forgets every solve."""

from __future__ import annotations

import fcntl
import os
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable

from .fingerprint import code_digest

CACHE_ENV = "BIPED_GAIT_CACHE"
OFF = "off"
CORE = Path(__file__).resolve().parents[1]  # biped_gait/core


@lru_cache(maxsize=1)
def core_digest() -> str:
    """SHA-256 of every module of the core (Python by its tokens, ``fingerprint.code_digest``;
    the native flow's C++ by its text): comments and docstrings do not change it."""
    names = sorted(str(path.relative_to(CORE)) for pattern in ("*.py", "*.cpp") for path in CORE.rglob(pattern))
    return code_digest("solves kept on disk", tuple(names))


def cache_directory() -> Path | None:
    """Where solves are kept, or None (``BIPED_GAIT_CACHE=off``)."""
    chosen = os.environ.get(CACHE_ENV, "")
    if chosen == OFF:
        return None
    if chosen:
        return Path(chosen)
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "biped_gait"


def _solved(kind: str, code: str, key: tuple, solve: Callable[[], Any]) -> Any:
    """``solve()``: what joblib keeps under (``kind``, ``code``, ``key``)."""
    return solve()


@lru_cache(maxsize=4)
def _memoized(directory: Path) -> Callable:
    from joblib import Memory  # the cache's library only when a cached solve is asked for

    return Memory(directory, verbose=0).cache(_solved, ignore=["solve"])


def cached(kind: str, key: tuple, solve: Callable[[], Any]) -> Any:
    """``solve()``'s result, from the cache if this code solved ``kind`` for ``key`` before (NumPy
    arrays, numbers, strings and frozen dataclasses of them), else solved and kept. One process or
    thread solves a key at a time: the others asking for it meanwhile wait for its answer (a lock
    file per key beside the results, left there)."""
    directory = cache_directory()
    if directory is None:
        return solve()
    from joblib import hash as key_hash

    code = core_digest()
    directory.mkdir(parents=True, exist_ok=True)
    with open(directory / f"{kind}-{key_hash((kind, code, key))}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file is closed
        return _memoized(directory)(kind, code, key, solve)
