"""One command under /usr/bin/time -v with a timeout, for the measuring scripts (sponza_bench.py,
scaling.py): exit code (or "timeout"), wall, user and system seconds, peak RSS, and the stderr tail.
On a timeout radray (the child of /usr/bin/time) is ended first, so that time still reports it."""

import os
import re
import signal
import subprocess
import time
from pathlib import Path


def run_timed(cmd, timeout_s, stderr_path=None):
    """Runs `cmd`; with `stderr_path`, its whole stderr (warnings, progress log) is also saved there."""
    start = time.time()
    p = subprocess.Popen(["/usr/bin/time", "-v", *cmd], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                         text=True, start_new_session=True)
    try:
        _, err = p.communicate(timeout=timeout_s)
        code = p.returncode
    except subprocess.TimeoutExpired:
        children = Path(f"/proc/{p.pid}/task/{p.pid}/children")
        for pid in children.read_text().split() if children.exists() else []:
            os.kill(int(pid), signal.SIGTERM)
        try:
            _, err = p.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            _, err = p.communicate()
        code = "timeout"

    def field(name):
        m = re.search(rf"{re.escape(name)}: ([^\n]+)", err)
        return float(m.group(1)) if m else None

    if stderr_path is not None:
        Path(stderr_path).write_text(err)
    rss_kb = field("Maximum resident set size (kbytes)")
    return {
        "command": " ".join(str(c) for c in cmd),
        "exit": code,
        "wall_s": round(time.time() - start, 1),
        "user_s": field("User time (seconds)"),
        "system_s": field("System time (seconds)"),
        "peak_rss_bytes": int(rss_kb * 1024) if rss_kb is not None else None,
        "stderr_tail": "\n".join(err.strip().splitlines()[-25:]),
    }
