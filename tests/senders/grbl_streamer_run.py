"""Streams a G-code program to a controller with grbl-streamer (PyPI), a
real grbl 1.1 sender: character counting against grbl's 128-byte RX
buffer, `?` status polling, a feed hold and a cycle start in the middle.
Prints one JSON object with what the sender saw.

usage: python3 grbl_streamer_run.py PORT PROGRAM
"""
import json
import sys
import threading
import time

from grbl_streamer import GrblStreamer

port, program = sys.argv[1], sys.argv[2]
seen = {"boot": 0, "errors": [], "alarms": [], "states": [], "processed": 0,
        "sent": 0, "settings": 0, "finished": False, "max_fill": 0}
done = threading.Event()
booted = threading.Event()


def callback(event, *data):
    if event == "on_boot":
        seen["boot"] += 1
        booted.set()
    elif event == "on_error":
        seen["errors"].append([str(d) for d in data])
        done.set()
    elif event == "on_alarm":
        seen["alarms"].append(str(data[0]))
    elif event == "on_stateupdate":
        if not seen["states"] or seen["states"][-1] != data[0]:
            seen["states"].append(data[0])
    elif event == "on_processed_command":
        seen["processed"] += 1
    elif event == "on_line_sent":
        seen["sent"] += 1
    elif event == "on_rx_buffer_percent":
        seen["max_fill"] = max(seen["max_fill"], data[0])
    elif event == "on_job_completed":
        seen["finished"] = True
        done.set()


grbl = GrblStreamer(callback)
grbl.setup_logging()
# grbl-streamer fills the RX buffer from the thread that starts the job and
# from its reader thread (on each `ok`) without a lock: with a controller
# that answers within microseconds the two interleave and a line is skipped
# or sent twice. One lock around its fill keeps its own counting sound.
fill_lock = threading.RLock()
unlocked_stream = grbl._stream


def locked_stream():
    with fill_lock:
        unlocked_stream()


grbl._stream = locked_stream
grbl.cnect(port, 115200)
if not booted.wait(10):
    print(json.dumps({"error": "no banner after the reset"}))
    sys.exit(1)
grbl.poll_interval = 0.05
grbl.poll_start()
# The sender asks `$#` and `$G` from its polling thread after the boot; their
# `ok`s must be in before the job starts (grbl-streamer's own streaming
# would otherwise run from two threads at once and skip a line).
deadline = time.time() + 10
while (grbl.hash_state_requested or grbl.gcode_parser_state_requested) and time.time() < deadline:
    time.sleep(0.05)
time.sleep(0.5)
grbl.load_file(program)
lines = grbl.buffer_size
grbl.job_run()
# A feed hold and a cycle start once a third of the program has gone.
while seen["processed"] < lines // 3 and not done.is_set():
    time.sleep(0.01)
grbl.hold()
time.sleep(0.3)
grbl.resume()
done.wait(300)
# Every line answered, then the motion to its end.
deadline = time.time() + 300
while seen["processed"] < lines and time.time() < deadline and not seen["errors"]:
    time.sleep(0.05)
while grbl.cmode != "Idle" and time.time() < deadline:
    time.sleep(0.05)
time.sleep(0.2)
grbl.poll_stop()
seen["lines"] = lines
seen["position"] = list(grbl.cmpos)
grbl.disconnect()
print(json.dumps(seen))
