"""Ctrl-C interrupts a long render promptly (the GIL is released; the engine polls for signals)."""
import signal
import subprocess
import sys
import time

import pytest

pytestmark = pytest.mark.smoke

SCRIPT = r"""
import signal, sys, time, models, sim
# A shell that starts jobs in the background without job control hands them SIGINT ignored; a user
# at a terminal has Python's default handler. Install it so the test is about the engine.
signal.signal(signal.SIGINT, signal.default_int_handler)
scene = models.named("mixed_sizes", n=20000)
cam = sim.Camera(width=1024, height=1024, focus_distance=6.0, coc_px=40)
table = sim.SampleTable.random(spp=256, seed=1)
print("started", flush=True)
t0 = time.perf_counter()
try:
    sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce", threads=2))
    print("finished", flush=True)
except KeyboardInterrupt:
    print(f"interrupted after {time.perf_counter() - t0:.2f} s", flush=True)
"""


def interrupt(proc: subprocess.Popen, ready) -> tuple[str, str, float]:
    """Call ready() (it waits for, and checks, the child's sign that it is busy), send SIGINT and wait:
    (stdout, stderr, seconds the child took to stop). The child is killed if it has not ended, so a
    failed check never leaves a long render running."""
    try:
        ready()
        t0 = time.perf_counter()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
        return out, err, time.perf_counter() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_ctrl_c_interrupts_render():
    with subprocess.Popen([sys.executable, "-c", SCRIPT], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True) as proc:
        def ready():
            assert proc.stdout.readline().strip() == "started"
            time.sleep(1.0)

        out, err, waited = interrupt(proc, ready)
    assert "interrupted" in out, (out, err)
    assert proc.returncode == 0, err
    assert waited < 5.0, f"took {waited:.1f} s to stop"
