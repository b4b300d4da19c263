# SPDX-License-Identifier: MIT
"""bench.py's worker processes: one per (method, thread count, case), started as ``python bench/bench.py --worker
METHOD --threads T --cpus C`` and pinned to its CPUs before it imports any library; the parent sends it JSON
lines on its stdin and reads its replies on a private pipe (its stdout; whatever a library prints goes to the
log)."""

from __future__ import annotations

import contextlib
import json
import os
import select
import subprocess
import sys
import time
import traceback
from pathlib import Path
from typing import IO, Any

from .common import allowed_cpus, pin, proc_status, thread_env
from .methods import Runner


def worker_main(method: str, threads: int, cpus: list[int]) -> int:
    """The worker's side: pinned to ``cpus``, it runs the parent's commands until "quit" or the end of its stdin."""
    # Pin before importing anything that starts threads (TBB and OpenMP size their pools from the mask).
    pin(cpus)
    proto = os.fdopen(os.dup(1), "w", buffering=1)
    os.dup2(2, 1)  # anything a library prints goes to the log, never into the protocol
    sys.stdout = sys.stderr

    def send(obj: dict[str, Any]) -> None:
        proto.write(json.dumps(obj) + "\n")
        proto.flush()

    try:
        runner = Runner(method, threads)
    except Exception as exc:  # noqa: BLE001 - reported to the parent
        send({"ok": False, "error": f"{type(exc).__name__}: {exc}"})
        return 1
    send({"ok": True, "version": runner.version, "affinity": allowed_cpus()})
    for line in sys.stdin:
        msg = json.loads(line)
        cmd = msg.get("cmd")
        reply: dict[str, Any]
        try:
            if cmd == "load":
                reply = runner.load(msg)
            elif cmd == "run":
                reply = runner.run()
            elif cmd == "mem":
                reply = dict(proc_status())
            elif cmd == "quit":
                send({"ok": True})
                return 0
            else:
                raise ValueError(f"unknown command {cmd!r}")
            reply["ok"] = True
        except Exception as exc:  # noqa: BLE001 - reported to the parent
            reply = {"ok": False, "error": f"{type(exc).__name__}: {exc}", "traceback": traceback.format_exc()}
        send(reply)
    return 0


class WorkerError(RuntimeError):
    pass


class WorkerTimeout(RuntimeError):
    pass


class Worker:
    """A method's worker process, pinned to ``cpus``; ``call`` sends one command and waits for its reply."""

    def __init__(self, script: Path, method: str, threads: int, cpus: list[int], log: IO[str], python: str):
        self.method = method
        self.baseline_kb = 0  # the worker's resident size after loading its case (the parent records it)
        log.write(f"\n===== worker {method} threads={threads} cpus={cpus}\n")
        log.flush()
        self.proc = subprocess.Popen(
            [
                python,
                str(script),
                "--worker",
                method,
                "--threads",
                str(threads),
                "--cpus",
                ",".join(map(str, cpus)),
            ],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=log,
            env=thread_env(threads),
        )
        self._buf = b""
        self.hello = self._reply(120.0)
        if not self.hello.get("ok"):
            self.close()
            raise WorkerError(f"{method}: {self.hello.get('error')}")

    def _reply(self, timeout: float | None) -> dict[str, Any]:
        deadline = None if timeout is None else time.monotonic() + timeout
        assert self.proc.stdout is not None  # Popen(stdout=PIPE)
        fd = self.proc.stdout.fileno()
        while b"\n" not in self._buf:
            remaining = None if deadline is None else deadline - time.monotonic()
            if remaining is not None and remaining <= 0:
                self.kill()
                raise WorkerTimeout(f"{self.method}: no reply within {timeout:.0f} s")
            ready, _, _ = select.select([fd], [], [], remaining)
            if not ready:
                continue
            chunk = os.read(fd, 1 << 16)
            if not chunk:
                code = self.proc.wait()
                raise WorkerError(f"{self.method}: worker exited with status {code}")
            self._buf += chunk
        line, self._buf = self._buf.split(b"\n", 1)
        reply: dict[str, Any] = json.loads(line)
        return reply

    def call(self, msg: dict[str, Any], timeout: float | None = None) -> dict[str, Any]:
        assert self.proc.stdin is not None  # Popen(stdin=PIPE)
        try:
            self.proc.stdin.write((json.dumps(msg) + "\n").encode())
            self.proc.stdin.flush()
        except BrokenPipeError as exc:
            raise WorkerError(f"{self.method}: worker is gone") from exc
        reply = self._reply(timeout)
        if not reply.get("ok"):
            raise WorkerError(f"{self.method}: {reply.get('error')}\n{reply.get('traceback', '')}")
        return reply

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()  # our own child, by its handle
            self.proc.wait()

    def close(self) -> None:
        if self.proc.poll() is None:
            try:
                self.call({"cmd": "quit"}, timeout=10)
            except (WorkerError, WorkerTimeout):
                pass
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.kill()
        for stream in (self.proc.stdin, self.proc.stdout):
            with contextlib.suppress(Exception):
                if stream is not None:
                    stream.close()
