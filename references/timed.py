"""One command under /usr/bin/time, for the reference scripts (baseline_rooms.py, time_to_error.py).

timed(cmd) -> (cpu_s, wall_s, max_rss_mib, stdout): CPU seconds are user + system of the whole process,
the honest figure on a shared machine. A non-zero exit raises RuntimeError with the stderr tail."""
import os
import subprocess
import tempfile


def timed(cmd):
    fd, tf = tempfile.mkstemp(prefix="radray_time_", suffix=".txt")
    os.close(fd)
    try:
        r = subprocess.run(["/usr/bin/time", "-f", "%U %S %e %M", "-o", tf] + cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise RuntimeError("exit %d: %s\n%s" % (r.returncode, " ".join(cmd), r.stderr.strip()[-800:]))
        u, s, e, m = open(tf).read().split()[-4:]
    finally:
        os.remove(tf)
    return float(u) + float(s), float(e), float(m) / 1024.0, r.stdout
