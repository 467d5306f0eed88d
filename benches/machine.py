"""The machine line the side-by-side bench scripts print: CPU model, logical CPUs, load
average and Python version, so a recorded figure says where and under what load it ran."""

import os
import platform


def cpu():
    """The CPU's model name (from /proc/cpuinfo on Linux)."""
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def machine_line():
    """`machine: <cpu>, N logical CPUs, load average L, Python V`."""
    return (f"machine: {cpu()}, {os.cpu_count()} logical CPUs, load average "
            f"{os.getloadavg()[0]:.1f}, Python {platform.python_version()}")
