"""How many CPUs this process may use: where rapidcomp runs work side by
side (the IK's two threads, the parse's second process, a big job's
helper process, the pool of two workers for several modules), it does so
only where there are two."""

from __future__ import annotations

import os

# A control group's CPU quota: (file, its "no quota" word), v2 then v1.
_QUOTAS = (("/sys/fs/cgroup/cpu.max", "max"), ("/sys/fs/cgroup/cpu/cpu.cfs_quota_us", "-1"))


def cores() -> float:
    """The CPUs this process may use: those it may run on, bounded by its
    control group's CPU quota (a container's --cpus; cgroup v2, else v1)."""
    try:
        n = float(len(os.sched_getaffinity(0)))
    except AttributeError:          # (not Linux: no mask, no control group)
        return float(os.cpu_count() or 1)
    for path, unlimited in _QUOTAS:
        try:
            with open(path) as f:
                quota = f.read().split()
            if len(quota) < 2:           # (v1: the period is a file of its own)
                with open(os.path.join(os.path.dirname(path), "cpu.cfs_period_us")) as f:
                    quota.append(f.read().strip())
            if quota[0] != unlimited:
                n = min(n, int(quota[0]) / int(quota[1]))
            break
        except (OSError, ValueError, IndexError, ZeroDivisionError):
            continue
    return n


# In a big job's helper process (side.py): it works beside the job, whose
# own work takes the other CPU.
_beside = False


def work_beside() -> None:
    """This process is a job's helper: its work runs one piece at a time."""
    global _beside
    _beside = True


def side_by_side() -> int:
    """How many pieces of work to run at once: two where the process may
    use two CPUs (and is not a job's helper), else one."""
    return 2 if not _beside and cores() >= 2 else 1
