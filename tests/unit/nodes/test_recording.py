"""The MCAP recorder: safe from several threads, and a killed recorder loses at most the last second.

Needs the ``mcap`` package (the ``record`` extra, part of ``dev``)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from cosleec.nodes import McapRecorder, read_recording

ROOT = Path(__file__).resolve().parents[3]

WRITER = """
import sys, time
from cosleec.nodes import McapRecorder
r = McapRecorder(sys.argv[1])
for i in range(50):
    r.write("decision", float(i), {"rule": "R1", "i": i})
time.sleep(1.6)  # longer than the flush period: all of it must be on disk now
print("written", flush=True)
time.sleep(60)  # killed here, never closed
"""


def test_a_killed_recorder_keeps_what_it_wrote_more_than_a_second_ago(tmp_path: Path) -> None:
    path = tmp_path / "crash.mcap"
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.Popen(
        [sys.executable, "-c", WRITER, str(path)], env=env, stdout=subprocess.PIPE, text=True
    )
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().strip() == "written"
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    assert proc.returncode == -signal.SIGKILL
    messages = read_recording(path)
    assert [m["i"] for _, m in messages] == list(range(50))
    assert {t for t, _ in messages} == {"/cosleec/decision"}


def test_writes_from_many_threads_all_arrive_whole_and_numbered_once(tmp_path: Path) -> None:
    path = tmp_path / "threads.mcap"
    recorder = McapRecorder(path)
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # switch threads as often as possible: overlapping writes
    try:

        def writer(k: int) -> None:
            for i in range(300):
                recorder.write(f"kind{k % 3}", float(i), {"writer": k, "i": i})

        threads = [threading.Thread(target=writer, args=(k,)) for k in range(8)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(old)
    recorder.close()
    recorder.write("decision", 0.0, {"late": True})  # after close: ignored, not an error
    messages = read_recording(path)
    assert len(messages) == 8 * 300
    assert sorted((m["writer"], m["i"]) for _, m in messages) == [
        (k, i) for k in range(8) for i in range(300)
    ]
    from mcap.reader import make_reader

    with path.open("rb") as fh:  # a closed recording is a complete MCAP file
        reader = make_reader(fh)
        seqs = [msg.sequence for _, _, msg in reader.iter_messages(log_time_order=False)]
        assert sorted(seqs) == list(range(1, 8 * 300 + 1))
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_count == 8 * 300


def test_a_quiet_recorder_flushes_within_a_second(tmp_path: Path) -> None:
    path = tmp_path / "quiet.mcap"
    recorder = McapRecorder(path)
    try:
        recorder.write("decision", 1.0, {"rule": "R1"})
        deadline = time.monotonic() + 3
        while not read_recording(path) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert [m["rule"] for _, m in read_recording(path)] == ["R1"]
    finally:
        recorder.close()
