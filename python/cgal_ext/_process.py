"""The environment a process that runs the library on large scans starts with, as point-detail sets it for itself:
glibc's malloc on transparent huge pages (doc/scaling.md, "Worker processes"); for a session that runs one large
call after another (the studio), also a malloc that keeps what it frees (doc/studio.md, "Start it")."""
import os

HUGE_PAGES = "glibc.malloc.hugetlb=1"
# One arena for every thread, no chunk of its own mapping, nothing given back: the memory one call frees is the
# next call's, whichever threads allocate it, instead of pages the kernel must clear and map again.
KEPT_MEMORY = ("glibc.malloc.arena_max=1", "glibc.malloc.mmap_max=0", "glibc.malloc.trim_threshold=1099511627776")


def tuned_environment(environ=None, keep_memory=False):
    """The variables to set before a process starts so that its large arrays are faulted in 2 MiB at a time instead
    of 4 KiB: GLIBC_TUNABLES with glibc.malloc.hugetlb=1 added to what it holds, unless GLIBC_TUNABLES already
    sets hugetlb or POINT_DETAIL_HUGE_PAGES is 0 (as for point-detail); with `keep_memory`, also each of
    KEPT_MEMORY's tunables that GLIBC_TUNABLES does not set. Empty when nothing is to be added."""
    environ = os.environ if environ is None else environ
    tunables = environ.get("GLIBC_TUNABLES", "")
    added = []
    if "glibc.malloc.hugetlb" not in tunables and environ.get("POINT_DETAIL_HUGE_PAGES") != "0":
        added.append(HUGE_PAGES)
    if keep_memory:
        added += [tunable for tunable in KEPT_MEMORY if tunable.split("=")[0] + "=" not in tunables]
    if not added:
        return {}
    return {"GLIBC_TUNABLES": ":".join(([tunables] if tunables else []) + added)}


def reexecute_tuned(argv, keep_memory=False):
    """Replaces this process by `argv` run with the tuned environment, when it lacks it (glibc reads its tunables
    only when a process starts); returns when there is nothing to change or the exec fails."""
    changes = tuned_environment(keep_memory=keep_memory)
    if changes:
        try:
            os.execve(argv[0], argv, {**os.environ, **changes})
        except OSError:
            pass
