#!/usr/bin/env python3
"""Writes the seed corpus of the fuzz targets from the request lines the
tests use: the protocol unit tests (core-nostd/src/protocol/tests/), the
host simulator's mixed session and the Kosenko / Krylenko programs
(host-sim/src/scenario.rs). Run from the repository root:

    python3 fuzz/seeds/make_seeds.py

It replaces fuzz/seeds/{protocol,length,gcode}/ (fuzz/seeds/words/ holds
inputs of the structured target and is kept as is).
"""
import hashlib
import os
import re
import shutil
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SEEDS = os.path.join(ROOT, "fuzz", "seeds")


def read(path):
    with open(os.path.join(ROOT, path), encoding="utf-8") as f:
        return f.read()


def xor(body):
    x = 0
    for b in body.encode():
        x ^= b
    return x


def with_checksum(body):
    return f"{body}*{xor(body):02X}"


def with_crc(body):
    return f"{body} ~{zlib.crc32((body + ' ').encode()) & 0xFFFFFFFF:08X}"


def unescape(lit):
    return (
        lit.replace("\\r", "\r")
        .replace("\\n", "\n")
        .replace("\\t", "\t")
        .replace("\\u{7f}", "\x7f")
        .replace("\\x00", "\x00")
        .replace("\\xff", "\xff")
        .replace("\\xfe", "\xfe")
        .replace('\\"', '"')
    )


COMMANDS = ("VER", "CFG", "ZERO", "MOVE", "ARC", "DRIVE", "POS", "SESSION", "FLY", "CONE", "FROB")


def is_request(l):
    w = l.strip().split(" ")[0].upper() if l.strip() else ""
    return (
        w in COMMANDS
        or w.startswith("@")
        or re.match(r"^[A-Za-z][0-9+\-.]", l.strip()) is not None
        or l.strip().startswith("*")
    )


# --- request lines of the protocol unit tests -------------------------------
TESTS = "core-nostd/src/protocol/tests"
tests = "".join(read(os.path.join(TESTS, f)) for f in sorted(os.listdir(os.path.join(ROOT, TESTS))))
lits = [unescape(l) for l in re.findall(r'"((?:[^"\\]|\\.)*)"', tests)]
lines = [l.rstrip("\r\n") for l in lits if is_request(l.split("\n")[0])]
# Numbered requests carry a CRC word, as the tests send them.
lines = [with_crc(l) if l.startswith("@") else l for l in lines]
lines += ["", "   \t ", "*00", with_checksum("MOVE X=0.005 Z=-0.015"),
          with_checksum(with_crc("@1 MOVE X=10 Z=-5")), "MOVE X=1~0000"]
long_line = "MOVE X=1 " + "0" * 112
lines.append(long_line)

# --- the mixed session of the host simulator ---------------------------------
scenario = read("host-sim/src/scenario.rs")
body = scenario[scenario.index("pub fn mixed_session"):]
body = body[: body.index("\n}\n")]
mixed = b""
for m in re.finditer(r'line\((&?crate::link::with_checksum\()?"((?:[^"\\]|\\.)*)"\)?\);', body):
    l = unescape(m.group(2))
    if m.group(1):
        l = with_checksum(l)
    lines.append(l)
    mixed += l.encode() + b"\r\n"
mixed += ("MOVE X=1 " + "0" * 200).encode() + b"\r\nPOS\r\n"
mixed += b"\x00\xff\x1b[A\x7f\xfe\r\nPOS\rPOS\nPOS\r\n\n"
for l in ["CFG HX=0.005 DIAM=1", "MOVE X=0 Z=0", "ZERO", "POS"]:
    mixed += l.encode() + b"\r\n"

# --- Kosenko table 21 and Krylenko programs ---------------------------------
rows = re.findall(r'row\(\d+, "([^"]+)", "([^"]+)"', scenario)
table21 = ["CFG HX=0.005 HZ=0.01 DIAM=0", "ZERO"] + [f"MOVE X={x} Z={z}" for z, x in rows] + ["MOVE X=0 Z=0"]
kr = scenario[scenario.index("pub fn krylenko()"):scenario.index("fn arc(")]
krylenko = ["CFG HX=0.005 HZ=0.01 DIAM=1", "ZERO"] + [
    f"MOVE X={x} Z={z}" for x, z in re.findall(r'\("([-0-9.]+)", "([-0-9.]+)"\)', kr)
] + ["MOVE X=0 Z=0"]
ka = scenario[scenario.index("pub fn krylenko_arcs()"):scenario.index("pub fn random_arcs")]
steps = re.findall(r'(Step::to|arc)\(("[^)]*)\)', ka)
krylenko_arcs = ["CFG HX=0.005 HZ=0.01 DIAM=1", "ZERO"]
for tol, pas in [("0.01", "FIN"), ("0.002", "FIN"), ("0.05", "ROUGH")]:
    for kind, args in steps:
        a = re.findall(r'"([^"]*)"', args)
        if kind == "Step::to":
            krylenko_arcs.append(f"MOVE X={a[0]} Z={a[1]}")
        else:
            ccw = "true" in args
            krylenko_arcs.append(
                f"ARC X={a[0]} Z={a[1]} I={a[2]} K={a[3]} DIR={'CCW' if ccw else 'CW'} TOL={tol} PASS={pas}"
            )
# The same programs as G-code (Fig. 22 with its R arcs, Fig. 24's hemisphere),
# and the direct arc of the Ø50 sphere.
fig22 = ["G00 X10 Z10", "N9 G01 X7.2 Z0 ; point 2", "G03 X12 Z-2.4 R2.4", "G01 Z-14.4",
         "G02 X17.2 Z-17 R2.6", "G01 X29.2", "G03 X38 Z-21.4 R4.4", "G01 X38 Z10",
         "G91 G01 Z-1", "G90 Z0", "N100 G01 M03 S500 T0101"]
fig24 = ["G00 X30 Z10", "G01 X20.8 Z0", "G03 X0 Z-10.4 R10.4", "G01 X0 Z10", "G00 X30 Z10",
         "G02X17.2Z-17R2.6 (point 5) F0.1", "g91 g42 x+1.5", "G40 X60", "G03 X19 Z-21.4 I0 K-4.4",
         "G03 X19 Z-21.4 R-4.4"]
sphere = ["ZERO", "MOVE X=21.986134 Z=11.9",
          "ARC X=25 Z=0 I=-21.986134 K=-11.9 DIR=CCW MODE=DIRECT F=35.5"]
reliable = ["SESSION TOKEN=77"] + [with_checksum(with_crc(l)) for l in [
    "@1 MOVE X=10 Z=-5", "@2 CFG HX=0.0025", "@2 CFG HX=0.0025", "@3 G01 X4", "@4 ZERO X=27.5325 Z=-0.015",
    "@5 POS"]] + [with_crc("@0 POS"), "@6 MOVE X=1"]

sessions = {
    "mixed_session": mixed,
    "table21": table21,
    "krylenko": krylenko,
    "krylenko_arcs": krylenko_arcs,
    "fig22_gcode": fig22,
    "fig24_gcode": fig24,
    "sphere_direct": sphere,
    "reliable": reliable,
}
lines += table21 + krylenko + krylenko_arcs + fig22 + fig24 + sphere + reliable


def write(target, name, data):
    d = os.path.join(SEEDS, target)
    os.makedirs(d, exist_ok=True)
    if name is None:
        name = hashlib.sha1(data).hexdigest()[:16]
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


for t in ("protocol", "length", "gcode"):
    shutil.rmtree(os.path.join(SEEDS, t), ignore_errors=True)

seen = set()
for l in lines:
    data = l.encode("latin-1") + b"\r\n"
    if data not in seen:
        seen.add(data)
        write("protocol", None, data)
for name, s in sessions.items():
    data = s if isinstance(s, bytes) else "".join(l + "\r\n" for l in s).encode()
    write("protocol", name, data)

# Numbers: every value after KEY= and after a G-code address letter, and the
# length parser's own examples.
numbers = set()
for l in lines:
    numbers.update(re.findall(r"=([^ ~*]+)", l))
    if re.match(r"^[A-Za-z][0-9+\-.]", l.strip()):
        numbers.update(re.findall(r"[A-Za-z]([0-9+\-.]+)", l))
length_rs = read("core-nostd/src/length.rs")
numbers.update(re.findall(r'(?:a|l|from_mm_str)\("([^"]*)"\)', length_rs))
numbers.update(["99999.99995", "-99999.99995", "99999.999949", "0.00005", "-0.00005", "٣", "1\u00a0"])
for n in sorted(numbers):
    write("length", None, n.encode())

blocks = [l for l in lines if re.match(r"^\s*[A-Za-z][0-9+\-.]", l)]
blocks += ["G01 X1 X2", "G01 G02", "G1.5", "Q5", "G01 X", "G01 X1 $", "G01 (open", "X1.1234567",
           "Z--1", "", "x-1.5", "N10 G01 X12",
           # Dwell times that round onto and beyond the top of the range.
           "G04 P99999.999999500", "G04 P99999.9999994", "G04 P99999.9995",
           # Numbers apart from their letters.
           "G0 X 2 Z\t-3", "T1 MG 71 M7 G4", "X1 2",
           # G41/G42 D: the tool whose nose compensates.
           "g42 d1", "G41 D0 G01 X2", "G42 D33", "G96 S100 G42 D1",
           # Probing, and a tool's offsets set from the block or from here.
           "G38.2 Z-50 F100", "G38.3 X10 F50", "G38.4 Z0 F20", "G38.5 X-1 Z-1 F20",
           "G10 L1 P1 X5 Z-3", "G10 L10 P2 Z0", "G10 L1 P32 R0.4 Q3", "G10 L10 P0 X1"]
for b in dict.fromkeys(blocks):
    write("gcode", None, b.encode())
print({t: len(os.listdir(os.path.join(SEEDS, t))) for t in ("protocol", "length", "gcode")})
