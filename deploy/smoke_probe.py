"""Memory probe for ``deploy/smoke-test --probe`` (loaded with ``panel serve --setup``).

On SIGUSR1 the server writes, to the file named by ``TUNNELSETTLE_PROBE_FILE``: its RSS, the
RSS after ``gc.collect()`` and after glibc's ``malloc_trim(0)``, the resident memory by kind of
mapping, the allocators' own totals (Python's arenas, glibc's heaps: where freed memory stays),
the modules loaded, the number of live objects by type,
the stage cache's entries and the number of Bokeh sessions alive. With
``TUNNELSETTLE_PROBE_TRACEMALLOC=1`` it also traces allocations from the start and reports the
15 source lines whose live memory grew most since the previous probe. A diagnostic, not part
of the deployment.
"""

from __future__ import annotations

import collections
import ctypes
import gc
import json
import os
import signal
import tracemalloc
from pathlib import Path

from dashboard.memory import glibc

_previous: list = []
if os.environ.get("TUNNELSETTLE_PROBE_TRACEMALLOC"):
    tracemalloc.start(12)


def _rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return round(int(line.split()[1]) / 1024, 1)
    return float("nan")


def _mapped_mb() -> dict:
    """Resident MB by kind of mapping (/proc/self/smaps): the main heap, anonymous mappings
    (thread heaps, large blocks, Python's arenas), thread stacks and files."""
    kinds, kind = collections.Counter(), None
    for line in Path("/proc/self/smaps").read_text().splitlines():
        head = line.split()
        if "-" in head[0] and ":" not in head[0]:
            name = head[5] if len(head) > 5 else ""
            if name == "[heap]":
                kind = "heap"
            elif not name:
                kind = "anonymous"
            else:
                kind = "stack" if name.startswith("[stack") else "file"
            kinds[kind + " mappings"] += 1
        elif head[0] == "Rss:":
            kinds[kind] += int(head[1])
    return {k: v if k.endswith("mappings") else round(v / 1024, 1) for k, v in kinds.items()}


def _allocator_stats() -> dict:
    """Python's small-object allocator (``sys._debugmallocstats``) and glibc's heaps
    (``malloc_info``), as the totals of their reports."""
    import re
    import sys
    import tempfile

    with tempfile.TemporaryFile("w+") as out:
        sys.stderr.flush()
        saved = os.dup(2)
        os.dup2(out.fileno(), 2)
        try:
            sys._debugmallocstats()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        out.seek(0)
        text = out.read()
    stats = {}
    keys = ("arenas allocated current", "bytes in allocated blocks", "bytes in available blocks")
    for key in keys:
        found = re.search(re.escape(key) + r"\s*=\s*([\d,]+)", text)
        if found:
            stats["pymalloc " + key] = int(found.group(1).replace(",", ""))
    libc = glibc()
    libc.open_memstream.restype = ctypes.c_void_p
    buffer, size = ctypes.c_char_p(), ctypes.c_size_t()
    stream = libc.open_memstream(ctypes.byref(buffer), ctypes.byref(size))
    libc.malloc_info(0, ctypes.c_void_p(stream))
    libc.fclose(ctypes.c_void_p(stream))
    info = ctypes.string_at(buffer, size.value).decode()
    libc.free(buffer)
    tail = info[info.rfind("</heap>") :]
    for kind in ("fast", "rest"):
        found = re.search(rf'<total type="{kind}" count="(\d+)" size="(\d+)"', tail)
        if found:
            stats[f"glibc free {kind} MB"] = round(int(found.group(2)) / 2**20, 1)
    for kind in ("current", "max"):
        found = re.search(rf'<system type="{kind}" size="(\d+)"', tail)
        if found:
            stats[f"glibc system {kind} MB"] = round(int(found.group(1)) / 2**20, 1)
    stats["glibc arenas"] = info.count("<heap nr=")
    found = re.search(r'<total type="mmap" count="(\d+)" size="(\d+)"', tail)
    if found:
        stats["glibc mmapped blocks"] = int(found.group(1))
        stats["glibc mmapped MB"] = round(int(found.group(2)) / 2**20, 1)
    return stats


def _name(o) -> str:
    return f"{type(o).__module__}.{type(o).__qualname__}"


def _chain(target, objects, ignore: set, depth: int = 12) -> list[str]:
    """A path of referrers from ``target`` back to a module, a class or a stack frame."""
    import types

    modules = {id(vars(m)): m.__name__ for m in list(__import__("sys").modules.values()) if m}
    ignore = {*ignore, id(objects)}
    path, seen, current = [], {id(target)}, target
    for _ in range(depth):
        found = gc.get_referrers(current)
        ignore.add(id(found))
        referrers = [
            r
            for r in found
            if id(r) not in ignore and id(r) not in seen and not isinstance(r, types.FrameType)
        ]
        ignore.add(id(referrers))
        if not referrers:
            path.append("(no referrer)")
            break
        if any(id(r) in modules for r in referrers):
            path.append("module " + next(modules[id(r)] for r in referrers if id(r) in modules))
            break
        current = next((r for r in referrers if not isinstance(r, list | dict)), referrers[0])
        seen.add(id(current))
        extra = ""
        if isinstance(current, dict):
            extra = " keys " + ",".join(map(str, list(current)[:5]))
        path.append(_name(current) + extra)
        if isinstance(current, type):
            break
    return path


def _ndarray_mb(objects) -> dict:
    """MB of the distinct NumPy buffers referred to by gc-tracked objects, by holder type."""
    import numpy as np

    seen, by_holder = set(), collections.Counter()
    for holder in objects:
        for item in gc.get_referents(holder):
            if isinstance(item, np.ndarray):
                base = item
                while isinstance(base.base, np.ndarray):
                    base = base.base
                if id(base) not in seen:
                    seen.add(id(base))
                    by_holder[_name(holder)] += base.nbytes
    top = dict(by_holder.most_common(8))
    return {"total": round(sum(by_holder.values()) / 1e6, 1),
            **{k: round(v / 1e6, 1) for k, v in top.items()}}  # fmt: skip


def _probe() -> dict:
    import panel as pn

    rss = _rss_mb()
    collected = gc.collect()
    rss_after_gc = _rss_mb()
    glibc().malloc_trim(0)
    objects = gc.get_objects()
    types = collections.Counter(f"{type(o).__module__}.{type(o).__qualname__}" for o in objects)
    caches = [o for o in objects if type(o).__name__ == "StageCache"]
    report = {
        "rss_mb": rss,
        "gc_collected": collected,
        "rss_after_gc_mb": rss_after_gc,
        "rss_after_trim_mb": _rss_mb(),
        "mapped_mb": _mapped_mb(),
        "allocators": _allocator_stats(),
        "gc_objects": len(objects),
        "modules": sorted(__import__("sys").modules),
        "types": dict(types),
        "cache_entries": [{k: len(v) for k, v in c._entries.items()} for c in caches],
        "ndarray_mb": _ndarray_mb(objects),
        "sessions": types.get("bokeh.server.session.ServerSession", 0),
        "state_watchers": dict(
            collections.Counter(
                getattr(w.fn, "__qualname__", repr(w.fn))
                for what in pn.state._param__private.watchers.values()
                for ws in what.values()
                for w in ws
            )
        ),
        "link_registry": len(__import__("panel.links").links.Callback.registry),
    }
    wanted = os.environ.get("TUNNELSETTLE_PROBE_CHAINS", "")
    report["chains"] = {}
    for name in filter(None, wanted.split(",")):
        candidates = [o for o in objects if _name(o) == name][:8]
        for i in range(len(candidates)):
            chain = _chain(candidates[i], objects, {id(candidates)})
            report["chains"][f"{name} #{i}"] = chain
        del candidates
    del objects, caches
    if tracemalloc.is_tracing():
        snapshot = tracemalloc.take_snapshot()
        if _previous:
            stats = snapshot.compare_to(_previous[-1], "traceback")[:15]
            report["tracemalloc_top"] = [
                f"{s.size_diff / 1e6:+.1f} MB in {s.count_diff:+d} blocks: "
                + " <- ".join(
                    f"{f.filename.rsplit('/', 2)[-1]}:{f.lineno}" for f in s.traceback[:6]
                )
                for s in stats
            ]
        _previous[:] = [snapshot]
    return report


def _on_signal(_signum, _frame) -> None:
    path = Path(os.environ["TUNNELSETTLE_PROBE_FILE"])
    text = json.dumps(_probe())
    partial = path.with_suffix(".part")
    partial.write_text(text)
    partial.replace(path)


signal.signal(signal.SIGUSR1, _on_signal)
