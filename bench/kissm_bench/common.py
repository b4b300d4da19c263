# SPDX-License-Identifier: MIT
"""What every benchmark shares: the repository's paths, the machine's description, CPU pinning and the worker
processes' environment, a process's memory counters, the command line a page quotes, and medians that skip
missing values."""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import datetime as _dt
import gc
import math
import os
import platform
import shlex
import statistics
import subprocess
import time
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

BENCH = Path(__file__).resolve().parent.parent  # bench/: the scripts, and results/
REPO = BENCH.parent
RESULTS = BENCH / "results"  # the committed results: each is what one page is rendered from
REPORTS = REPO / "docs" / "reports"  # the generated pages: every benchmark's default --out
SHARED_DATA = REPO.parent / "shared" / "data"

#: The distributions machine_info records, in the order the pages list them.
MACHINE_PACKAGES = ("kissm", "kiss-matcher", "open3d-cpu", "open3d", "small-gicp", "numpy", "matplotlib")
#: What sizes the thread pools of numpy's BLAS, OpenMP and their kin: a worker of T threads gets T in each.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS")


DATA_HELP = "the data folder (KISSM_DATA_DIR, else ../shared/data)"


def no_data(tag: str, why: str) -> int:
    """A benchmark's exit without the data it needs: the line tools/test.sh lists as a skip ("TAG: skipped: WHY"),
    and status 0."""
    print(f"{tag}: skipped: {why} (set --data or KISSM_DATA_DIR)", flush=True)
    return 0


def default_data() -> Path:
    """The real data: KISSM_DATA_DIR, else ../shared/data beside the checkout."""
    return Path(os.environ.get("KISSM_DATA_DIR") or SHARED_DATA)


def add_data_option(parser: argparse.ArgumentParser, text: str = DATA_HELP) -> None:
    parser.add_argument("--data", type=Path, default=default_data(), help=text)


def add_output_options(parser: argparse.ArgumentParser, writes: str, committed: Path, raw_name: str) -> None:
    """--out, --raw and --report-from of a benchmark that writes ``writes`` (its page, in OUT) and, with the default
    --out, its reduced results to ``committed``."""
    parser.add_argument("--out", type=Path, default=REPORTS, help=f"writes {writes} (default docs/reports)")
    parser.add_argument(
        "--raw",
        type=Path,
        default=None,
        help=f"also write the full raw results JSON here (default: OUT/{raw_name}, except with the default --out, "
        f"whose page's reduced results go to {repo_relative(committed)})",
    )
    parser.add_argument(
        "--report-from",
        type=Path,
        default=None,
        help="only rewrite the page from saved results (reduced .json.gz or raw .json)",
    )


def is_committed(out: Path, smoke: bool = False) -> bool:
    """Whether a run writes the committed page (the default --out, not a smoke run): only such a run's results go
    to bench/results/."""
    return not smoke and out.resolve() == REPORTS.resolve()


def repo_relative(path: Path) -> str:
    """``path`` as the pages quote it: relative to the checkout when it is inside it."""
    resolved = path.resolve()
    return str(resolved.relative_to(REPO)) if resolved.is_relative_to(REPO) else str(path)


def explicit_options(argv: Sequence[str]) -> set[str]:
    """The options given on the command line (``--name`` or ``--name=value``), to tell them from defaults."""
    return {a.split("=")[0] for a in argv if a.startswith("--")}


def command_line(script: str, argv: Sequence[str]) -> str:
    """The command a page quotes: bench/run.sh's own (KISSM_BENCH_COMMAND) or this script's."""
    command = os.environ.get("KISSM_BENCH_COMMAND") or f"python bench/{script} " + " ".join(
        shlex.quote(a) for a in argv
    )
    return command.strip()


def script_parser(doc: str | None) -> argparse.ArgumentParser:
    """A benchmark's options: the first paragraph of its module's docstring as the description, as written."""
    return argparse.ArgumentParser(
        description=(doc or "").split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )


def now() -> str:
    """The local time with its offset, to the second (the pages' start and end of a run)."""
    return _dt.datetime.now().astimezone().isoformat(timespec="seconds")


def args_record(args: Any, leave_out: Iterable[str] = ()) -> dict[str, Any]:
    """A run's options as its results record them (paths as strings)."""
    skip = set(leave_out)
    return {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items() if k not in skip}


def run_meta(
    script: str, argv: Sequence[str], args: Any, leave_out: Iterable[str] = (), **extra: Any
) -> dict[str, Any]:
    """The description a run's results start with: the command, the options, the start, the load average, the
    machine, and ``extra``."""
    return {
        "command": command_line(script, argv),
        "args": args_record(args, leave_out),
        "started": now(),
        "load_start": os.getloadavg(),
        "machine": machine_info(),
        **extra,
    }


def finish_meta(meta: dict[str, Any], t0: float) -> None:
    """``meta`` completed when the run ends (``t0``: its ``time.monotonic()`` at the start)."""
    meta["duration_s"] = time.monotonic() - t0
    meta["load_end"] = os.getloadavg()
    meta["finished"] = now()


# ---- threads and CPUs -------------------------------------------------------------------------------------


def cpus_for(threads: int) -> list[int]:
    """The first ``threads`` CPUs this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        available = sorted(os.sched_getaffinity(0))
    else:
        available = list(range(os.cpu_count() or 1))
    if threads > len(available):
        raise SystemExit(f"bench: {threads} threads asked for, but only CPUs {available} are available")
    return available[:threads]


def pin(cpus: list[int]) -> None:
    """Pins this process to ``cpus`` (as ``taskset`` would); threads started later inherit the mask."""
    if cpus and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, cpus)


def allowed_cpus() -> list[int]:
    """The CPUs this process may run on ([] where the platform does not say)."""
    return sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []


def thread_env(threads: int) -> dict[str, str]:
    """The environment of a worker process of ``threads`` threads: its libraries size their pools from it."""
    env = dict(os.environ)
    for var in THREAD_VARIABLES:
        env[var] = str(threads)
    env["PYTHONUNBUFFERED"] = "1"
    return env


# ---- a process's memory ---------------------------------------------------------------------------------


def proc_status() -> dict[str, int]:
    """This process's resident size and its peak (``VmRSS``, ``VmHWM``), in kB."""
    out = {}
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(("VmRSS:", "VmHWM:")):
                key, value = line.split(":", 1)
                out[key] = int(value.split()[0])  # kB
    return out


def trim_heap() -> None:
    """Returns the freed heap to the OS, so that the resident size counts what is in use."""
    gc.collect()
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL("libc.so.6").malloc_trim(0)


def reset_peak() -> None:
    """Resets ``VmHWM`` to the current resident size."""
    # Writing 5 resets VmHWM to the current RSS (Linux >= 4.0). Without it the peak includes loading.
    with contextlib.suppress(OSError):
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")


# ---- numbers --------------------------------------------------------------------------------------------


def med(values: Iterable[float | None]) -> float | None:
    """The median of the known values (None skipped), or None when none is known."""
    kept = [v for v in values if v is not None]
    return statistics.median(kept) if kept else None


def finite(value: float) -> float | None:
    """``value``, or None when it is not finite (JSON has no NaN)."""
    value = float(value)
    return value if math.isfinite(value) else None


# ---- the machine ------------------------------------------------------------------------------------------


def package_versions(dists: Iterable[str]) -> dict[str, str | None]:
    """The installed version of each distribution, None where it is not installed (every bench's report)."""
    from importlib import metadata

    out: dict[str, str | None] = {}
    for dist in dists:
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = None
    return out


def machine_info() -> dict[str, Any]:
    """The machine, the installed packages and the checkout's commit, as every page describes its run."""
    info: dict[str, Any] = {
        "platform": platform.platform(),
        "python": platform.python_version(),
        "cpus_online": os.cpu_count(),
    }
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                info["cpu"] = line.split(":", 1)[1].strip()
                break
    with contextlib.suppress(OSError):
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                info["mem_total_gb"] = round(int(line.split()[1]) / 2**20, 1)
    if hasattr(os, "sched_getaffinity"):
        info["cpus_allowed"] = allowed_cpus()
    versions = package_versions(MACHINE_PACKAGES)
    info["packages"] = {dist: version for dist, version in versions.items() if version is not None}
    with contextlib.suppress(Exception):
        head = subprocess.run(
            ["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True, text=True, timeout=10
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(REPO), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            timeout=10,
        ).stdout.strip()
        info["git"] = head + (" (with uncommitted changes)" if dirty else "")
    with contextlib.suppress(Exception):
        import kissm

        info["kissm_library"] = kissm.library_path
    return info


def ordered_packages(packages: dict[str, Any]) -> list[tuple[str, Any]]:
    """A run's packages in the order machine_info records them (the saved results sort their keys)."""
    known = [(d, packages[d]) for d in MACHINE_PACKAGES if d in packages]
    return known + sorted((d, v) for d, v in packages.items() if d not in MACHINE_PACKAGES)
