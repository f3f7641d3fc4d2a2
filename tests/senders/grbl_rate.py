"""Streams a G-code program to a grbl controller by character counting
(the 128-byte RX buffer of grbl 1.1), polling `?` every 200 ms as senders
do, and prints one JSON object: the lines, the seconds until the last `ok`
(the rate a sender reaches), and the seconds until the controller reports
`Idle` again (the whole run, against the program's planned time).

usage: python3 grbl_rate.py PORT PROGRAM
"""
import json
import re
import sys
import threading
import time

import serial

port, program = sys.argv[1], sys.argv[2]
lines = []
for raw in open(program, encoding="latin-1"):
    line = re.sub(r"\(.*?\)|;.*", "", raw).strip()
    if line and not line.startswith("%"):
        lines.append(line)

link = serial.Serial(port, 115200, timeout=0.05)
# The greeting (a board greets the sender that opens its port).
deadline = time.time() + 5
while time.time() < deadline and b"Grbl" not in link.readline():
    pass

lock = threading.Lock()
state = {"ok": 0, "errors": [], "states": [], "idle_at": None}
in_flight = []
done = threading.Event()


def reader():
    while not done.is_set():
        raw = link.readline()
        if not raw:
            continue
        text = raw.decode("latin-1").strip()
        with lock:
            if text == "ok" or text.startswith("error:"):
                state["ok"] += 1
                if text.startswith("error:"):
                    state["errors"].append(text)
                if in_flight:
                    in_flight.pop(0)
            elif text.startswith("<"):
                s = text[1:].split("|")[0]
                if not state["states"] or state["states"][-1] != s:
                    state["states"].append(s)
                if s == "Idle" and state["ok"] == len(lines) and state["idle_at"] is None:
                    state["idle_at"] = time.time()


def poller():
    while not done.is_set():
        link.write(b"?")
        time.sleep(0.2)


threading.Thread(target=reader, daemon=True).start()
threading.Thread(target=poller, daemon=True).start()
t0 = time.time()
for line in lines:
    data = (line + "\n").encode()
    while True:
        with lock:
            if sum(in_flight) + len(data) <= 128:
                in_flight.append(len(data))
                break
        time.sleep(0.0005)
    link.write(data)
while True:
    with lock:
        if state["ok"] >= len(lines):
            break
    time.sleep(0.001)
t_ok = time.time() - t0
while True:
    with lock:
        if state["idle_at"] is not None:
            break
    time.sleep(0.01)
done.set()
print(json.dumps({
    "lines": len(lines),
    "ok_s": round(t_ok, 3),
    "lines_per_s": round(len(lines) / t_ok, 1),
    "idle_s": round(state["idle_at"] - t0, 3),
    "errors": state["errors"],
    "states": state["states"][:20],
}))
