"""How long a command runs before campar catches stop signals: from the spawn until
/proc/<pid>/status shows SIGUSR1 caught (campar's handler; Python installs none of its own
for it). Prints the median, 90th percentile and maximum over N spawns.

    python benchmarks/signal_window.py 20 .venv/bin/python -m campar.cli run jobs/smoke.yaml
    python benchmarks/signal_window.py 20 .venv/bin/python -c \
        "import signal, time; signal.signal(signal.SIGUSR1, print); time.sleep(5)"

The second is the interpreter's own share: a bare Python that installs one handler first.
Each spawned command is killed as soon as its handler is seen (a run is not computed).
"""

import signal
import statistics
import subprocess
import sys
import time
from pathlib import Path


def caught(pid: int, signum: int = signal.SIGUSR1) -> bool:
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    masks = [line.split()[1] for line in status.splitlines() if line.startswith("SigCgt:")]
    return bool(masks) and bool(int(masks[0], 16) >> (signum - 1) & 1)


def main() -> None:
    count, command = int(sys.argv[1]), sys.argv[2:]
    times = []
    for _ in range(count):
        start = time.perf_counter()
        proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        while not caught(proc.pid) and proc.poll() is None:
            time.sleep(0.0005)
        times.append(time.perf_counter() - start)
        proc.kill()
        proc.wait()
    times.sort()
    print(
        f"median {1000 * statistics.median(times):.0f} ms, 90% {1000 * times[int(0.9 * count)]:.0f}"
        f" ms, max {1000 * times[-1]:.0f} ms over {count} starts: {' '.join(command)}"
    )


if __name__ == "__main__":
    main()
