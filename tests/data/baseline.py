#!/usr/bin/env python3
"""Regenerate tests/data/BASELINE.md: how host-sim handles every program of the corpus.

For each row of SOURCES.md (file, dialect) it runs `host-sim check FILE --dialect D`, and
`host-sim run FILE --dialect D` when the check passes, then writes one table row per file and a
summary of the refusals by cause.

    python3 tests/data/baseline.py [path/to/host-sim]

The host-sim binary defaults to $HOST_SIM, then target/release/host-sim of the workspace.
Only the Python standard library is used.
"""

import collections
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def host_sim_path():
    if len(sys.argv) > 1:
        return sys.argv[1]
    return os.environ.get("HOST_SIM", os.path.join(ROOT, "target", "release", "host-sim"))


def corpus():
    """(file, dialect) for every row of SOURCES.md's main table."""
    rows = []
    with open(os.path.join(HERE, "SOURCES.md"), encoding="utf-8") as f:
        for line in f:
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) < 7 or not cells[0].startswith("`"):
                continue
            path = cells[0].strip("`")
            dialect = re.match(r"`(\w+)`", cells[5]).group(1)
            rows.append((path, dialect))
    return rows


REFUSAL = re.compile(r"^(?P<file>.+?):(?P<line>\d+):(?P<col>\d+): (?P<what>.*)$")


def cause_of(message):
    """The refusal's cause, the same for every occurrence: no quoted block, no axis letter."""
    message = re.sub(r" \(in `.*`\)$", "", message)
    message = re.sub(r"^[XZ] more than 15 decimals$", "X/Z more than 15 decimals", message)
    return message


def check(host_sim, path, dialect):
    proc = subprocess.run([host_sim, "check", path, "--dialect", dialect],
                          cwd=HERE, capture_output=True, text=True, timeout=600)
    refusals = []
    for line in (proc.stdout + proc.stderr).splitlines():
        m = REFUSAL.match(line)
        if m and m.group("file") == path:
            refusals.append((int(m.group("line")), int(m.group("col")), m.group("what")))
    return proc.returncode, refusals, (proc.stdout + proc.stderr).strip()


def run(host_sim, path, dialect):
    proc = subprocess.run([host_sim, "run", path, "--dialect", dialect],
                          cwd=HERE, capture_output=True, text=True, timeout=1800)
    lines = (proc.stdout + proc.stderr).strip().splitlines()
    summary = lines[0].split(": ", 1)[-1] if lines else ""
    cycle = next((l for l in lines if l.startswith("cycle time")), "")
    return proc.returncode, summary, cycle


# Groups of causes, in the order the what-if ladder of BASELINE.md adds them.
GROUPS = [
    ("G80 and G64 in headers (modal words with nothing to do here)",
     re.compile(r"^G(80|64) not supported$")),
    ("machine M-codes (chip conveyor, tailstock, gear range, live tool, clamps)",
     re.compile(r"^M\d+ not supported$")),
    ("turning cycles and spindle-synchronised moves (G70-G76, G71.1/G71.2, G90/G92/G94, G33)",
     re.compile(r"canned cycles not supported$|^G71\.[12] not supported$|^G33 threading not supported$")),
    ("dynamic nose compensation G41.1/G42.1", re.compile(r"^G4[12]\.1 not supported$")),
    ("characters outside printable ASCII (control characters, UTF-8 in comments)",
     re.compile(r"^not printable ASCII$")),
]


def md(text):
    return text.replace("|", "\\|")


def main():
    host_sim = host_sim_path()
    version = subprocess.run([host_sim, "-V"], capture_output=True, text=True).stdout.strip()
    tree = subprocess.run(["git", "-C", os.path.dirname(os.path.abspath(host_sim)), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True).stdout.strip()
    if tree:
        version += f" from a work tree at {tree}"
    rows = []
    causes = collections.defaultdict(lambda: {"files": [], "lines": 0})
    per_file_causes = {}
    for path, dialect in corpus():
        rc, refusals, raw = check(host_sim, path, dialect)
        file_causes = collections.Counter(cause_of(w) for _, _, w in refusals)
        per_file_causes[path] = file_causes
        for cause, n in file_causes.items():
            causes[cause]["files"].append(path)
            causes[cause]["lines"] += n
        if rc == 0 and not refusals:
            run_rc, summary, cycle = run(host_sim, path, dialect)
            outcome = "runs to the end" if run_rc == 0 else f"run exit {run_rc}"
            rows.append((path, dialect, outcome, "0", "—", f"{summary}; {cycle}"))
        else:
            if refusals:
                line, col, what = refusals[0]
                first = f"{line}:{col}: {what}"
            else:
                first = raw.splitlines()[-1] if raw else f"exit {rc}"
            rows.append((path, dialect, "refused", str(len(refusals)), first, "not run (check refused)"))

    out = []
    out.append("# Baseline: how the controller handles the corpus today\n")
    out.append(f"Generated by `tests/data/baseline.py` with `{version}` "
               "(`host-sim check FILE --dialect D`, and `host-sim run FILE --dialect D` where the check passes). "
               "*Refused lines* counts every line `check` lists; *First refusal* is the first of them, "
               "in the controller's words.\n")
    out.append("Reading it: `check` names the first problem of each line, so a line refused for one word may "
               "hide another; passing `check` is needed to run but does not prove the run ends well (the `run` "
               "column does). The dialect is the one SOURCES.md gives each file; README.md lists the programs "
               "to read with care (not plain turning, malformed, or whose result depends on a setting).\n")
    passed = sum(1 for r in rows if r[2] == "runs to the end")
    out.append(f"{passed} of {len(rows)} programs run to the end; {len(rows) - passed} are refused.\n")
    out.append("| File | Dialect | Result | Refused lines | First refusal (line:col: message) | Run |")
    out.append("| --- | --- | --- | --- | --- | --- |")
    for path, dialect, outcome, n, first, runinfo in rows:
        out.append(f"| `{path}` | {dialect} | {outcome} | {n} | {md(first)} | {md(runinfo)} |")

    out.append("\n## Refusals by cause\n")
    out.append("*Files* counts the programs with at least one line refused for that cause; *only cause* counts "
               "the programs this cause alone keeps from running (fix it and they pass `check`).\n")
    out.append("| Cause (controller's message) | Files | Refused lines | Only cause | Example files |")
    out.append("| --- | --- | --- | --- | --- |")
    order = sorted(causes.items(), key=lambda kv: (-len(kv[1]["files"]), -kv[1]["lines"], kv[0]))
    for cause, info in order:
        only = sum(1 for f in info["files"] if set(per_file_causes[f]) == {cause})
        examples = ", ".join(f"`{f}`" for f in info["files"][:3])
        if len(info["files"]) > 3:
            examples += f" (+{len(info['files']) - 3})"
        out.append(f"| {md(cause)} | {len(info['files'])} | {info['lines']} | {only} | {examples} |")

    out.append("\n## What would run if a group of causes were lifted\n")
    out.append("Cumulative: each row adds one group of causes to those above it and counts the programs that "
               "would then pass `check` (no other refusal left).\n")
    out.append("| Causes lifted (cumulative) | Programs passing `check` |")
    out.append("| --- | --- |")
    lifted = set()
    out.append(f"| none (today) | {sum(1 for c in per_file_causes.values() if not c)} |")
    every = set(causes)
    for name, pattern in GROUPS:
        lifted |= {c for c in every if pattern.search(c)}
        n = sum(1 for c in per_file_causes.values() if set(c) <= lifted)
        out.append(f"| + {name} | {n} |")
    left = sorted((f, sorted(set(c) - lifted)) for f, c in per_file_causes.items() if set(c) - lifted)
    out.append("\nStill refused after all of these:\n")
    for f, rest in left:
        out.append(f"- `{f}`: " + "; ".join(md(r) for r in rest))

    with open(os.path.join(HERE, "BASELINE.md"), "w", encoding="utf-8") as f:
        f.write("\n".join(out) + "\n")
    print(f"{len(rows)} files, {passed} run to the end; causes: {len(causes)}")


if __name__ == "__main__":
    main()
