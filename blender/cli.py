"""The `sticky-lips` executable, run as a separate process (never linked into Blender).

`run` waits for a short command (`face`, `export`); `Job` starts a long one (`run --progress
json`) and is polled from a timer: its stdout and stderr are read by two threads into queues,
so that Blender's main thread never blocks on a pipe. No bpy here.
"""

import json
import os
import queue
import shutil
import signal
import subprocess
import sys
import threading

EXECUTABLE = "sticky-lips"


class CliError(Exception):
    """A failure to show the user: one readable message, no traceback."""


def find(configured):
    """The executable: `configured` (the preference) if set, else `sticky-lips` on PATH."""
    if configured:
        path = os.path.abspath(os.path.expanduser(configured))
        if not os.path.isfile(path):
            raise CliError(f"the sticky-lips executable set in the preferences does not exist: {path}")
        if not os.access(path, os.X_OK):
            raise CliError(f"the sticky-lips executable set in the preferences is not executable: {path}")
        return path
    found = shutil.which(EXECUTABLE)
    if not found:
        raise CliError(
            "sticky-lips was not found on PATH: install it (cargo install --path cli) or set its "
            "path in Edit > Preferences > Add-ons > Sticky Lips"
        )
    return found


def _message(stderr, args):
    """The CLI's error text (its `error: ` prefix dropped), or a line naming the command."""
    text = (stderr or "").strip()
    if text.startswith("error: "):
        text = text[len("error: "):]
    return text or f"{os.path.basename(args[0])} {args[1]} failed with no message"


def run(args, cwd=None):
    """Runs `args` to completion; its stdout, or CliError with the CLI's own message."""
    try:
        p = subprocess.run(args, cwd=cwd, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    except OSError as e:
        raise CliError(f"could not start {args[0]}: {e}")
    if p.returncode != 0:
        raise CliError(_message(p.stderr, args))
    return p.stdout


def _pump(stream, q):
    for line in iter(stream.readline, ""):
        q.put(line)
    stream.close()
    q.put(None)


class Job:
    """A running `sticky-lips` command whose stdout is JSON lines (`run --progress json`).

    `poll()` takes what arrived: the progress events (`self.events`, the last one in
    `self.last`) and whether the process has exited (`self.returncode`)."""

    def __init__(self, args, cwd=None):
        self.args = list(args)
        kw = {}
        if sys.platform == "win32":
            # CTRL_BREAK_EVENT reaches only a process group of its own
            kw["creationflags"] = subprocess.CREATE_NEW_PROCESS_GROUP
        try:
            self.proc = subprocess.Popen(
                self.args,
                cwd=cwd,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
                bufsize=1,
                **kw,
            )
        except OSError as e:
            raise CliError(f"could not start {self.args[0]}: {e}")
        self._out, self._err = queue.Queue(), queue.Queue()
        self._open = 2
        for stream, q in ((self.proc.stdout, self._out), (self.proc.stderr, self._err)):
            threading.Thread(target=_pump, args=(stream, q), daemon=True).start()
        self.events = []
        self.last = None
        self.stderr = []
        self.returncode = None
        self.interrupt_sent = False

    def poll(self):
        """Reads what arrived; True once the process has exited and both pipes are drained."""
        for q, sink in ((self._out, None), (self._err, self.stderr)):
            while True:
                try:
                    line = q.get_nowait()
                except queue.Empty:
                    break
                if line is None:
                    self._open -= 1
                    continue
                if sink is not None:
                    sink.append(line)
                    continue
                line = line.strip()
                if not line:
                    continue
                try:
                    ev = json.loads(line)
                except ValueError:
                    continue  # not one of the JSON lines (nothing else is printed on stdout)
                if isinstance(ev, dict):
                    self.events.append(ev)
                    self.last = ev
        if self._open == 0 and self.returncode is None:
            self.returncode = self.proc.wait()
        return self.returncode is not None

    def interrupt(self):
        """Asks the run to stop between two steps, as Ctrl+C in a terminal does: it keeps the
        frames written so far and exits with status 130."""
        if self.returncode is not None or self.proc.poll() is not None:
            return
        self.interrupt_sent = True
        if sys.platform == "win32":
            self.proc.send_signal(signal.CTRL_BREAK_EVENT)
        else:
            self.proc.send_signal(signal.SIGINT)

    def kill(self):
        if self.proc.poll() is None:
            self.proc.kill()

    def error_text(self):
        return _message("".join(self.stderr), self.args)
