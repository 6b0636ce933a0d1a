"""The environment a process that runs the library on large scans starts with, as point-detail sets it for itself:
glibc's malloc on transparent huge pages (doc/scaling.md, "Worker processes")."""
import os

HUGE_PAGES = "glibc.malloc.hugetlb=1"


def tuned_environment(environ=None):
    """The variables to set before a process starts so that its large arrays are faulted in 2 MiB at a time instead
    of 4 KiB: GLIBC_TUNABLES with glibc.malloc.hugetlb=1 added to what it holds. Empty when GLIBC_TUNABLES already
    sets hugetlb or POINT_DETAIL_HUGE_PAGES is 0 (as for point-detail)."""
    environ = os.environ if environ is None else environ
    tunables = environ.get("GLIBC_TUNABLES", "")
    if "glibc.malloc.hugetlb" in tunables or environ.get("POINT_DETAIL_HUGE_PAGES") == "0":
        return {}
    return {"GLIBC_TUNABLES": f"{tunables}:{HUGE_PAGES}" if tunables else HUGE_PAGES}


def reexecute_tuned(argv):
    """Replaces this process by `argv` run with the tuned environment, when it lacks it (glibc reads its tunables
    only when a process starts); returns when there is nothing to change or the exec fails."""
    changes = tuned_environment()
    if changes:
        try:
            os.execve(argv[0], argv, {**os.environ, **changes})
        except OSError:
            pass
