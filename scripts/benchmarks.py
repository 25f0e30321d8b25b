#!/usr/bin/env python3
"""docs/BENCHMARKS.md, generated from docs/benchmarks/: one current table per topic.

    python3 scripts/benchmarks.py           write docs/BENCHMARKS.md (`make benchmarks`)
    python3 scripts/benchmarks.py --check   exit 1 if it differs from what would be written,
                                            or if a topic's text is dated

docs/benchmarks/topics.toml lists the topics in order: each `id` has `<id>.md`, the method
(what is measured and how, in the present tense: no date, commit or version), and `<id>.csv`,
one row per measurement, every run's rows kept: `date` (YYYY-MM-DD), `commit` (may be
empty), `machine`, `command`, then the table's own columns. The current table holds, for
each value of the topic's `key` columns, the row of the latest date (the last of that date in
the file); the date, commit, machine and command of the rows shown are printed under it. A
new run appends its rows to the CSV, and `make benchmarks` redraws the page.
"""

import csv
import re
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DIR = ROOT / "docs" / "benchmarks"
OUT = ROOT / "docs" / "BENCHMARKS.md"
META = ["date", "commit", "machine", "command"]

# What a topic's text may not say: it describes the method, and the CSV dates the numbers.
DATED = [
    (re.compile(r"\b20\d\d-\d\d-\d\d\b"), "a date"),
    (re.compile(r"\bversion \d+\b"), "a stage version"),
    (re.compile(r"\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,12}\b"), "a commit"),
]


def read_rows(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head, body = rows[0], rows[1:]
    if head[: len(META)] != META:
        sys.exit(f"{path}: the first columns must be {', '.join(META)}; found {head[:4]}")
    for n, r in enumerate(body, start=2):
        if len(r) != len(head):
            sys.exit(f"{path}, line {n}: {len(r)} fields where the header has {len(head)}")
        if not re.fullmatch(r"20\d\d-\d\d-\d\d", r[0]):
            sys.exit(f"{path}, line {n}: date '{r[0]}' is not YYYY-MM-DD")
    return head, body


def current(head, body, key):
    """The latest row of each key, in the order the keys first appear."""
    index = [head.index(k) for k in key]
    latest, order = {}, []
    for r in body:
        k = tuple(r[i] for i in index)
        if k not in latest:
            order.append(k)
            latest[k] = r
        elif r[0] >= latest[k][0]:
            latest[k] = r
    return [latest[k] for k in order], len(body)


def table(head, rows, per_row=False):
    """The table of `rows`; `per_row` adds each row's command and when and where it ran."""
    cols = head[len(META):] + (["command", "measured"] if per_row else [])

    def cells(r):
        own = r[len(META):]
        if per_row:
            date, commit, machine, command = r[: len(META)]
            at = f" at {commit}" if commit else ""
            own = own + [command, f"{date}{at}, {machine}"]
        return own

    out = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    out += ["| " + " | ".join(cells(r)) + " |" for r in rows]
    return out


def provenance(rows, total):
    runs = sorted({tuple(r[: len(META)]) for r in rows})
    parts = []
    for date, commit, machine, command in runs:
        at = f" at {commit}" if commit else ""
        parts.append(f"{command}{at}, {date}, {machine}")
    earlier = total - len(rows)
    tail = f"; {earlier} earlier row(s) in the CSV" if earlier else ""
    return "Measured by " + "; ".join(parts) + tail + "."


def render(topics_dir):
    topics = tomllib.loads((topics_dir / "topics.toml").read_text())["topic"]
    out = [(topics_dir / "header.md").read_text().rstrip(), ""]
    problems = []
    for t in topics:
        text = (topics_dir / f"{t['id']}.md").read_text().rstrip()
        for pattern, what in DATED:
            for m in pattern.finditer(text):
                problems.append(f"{topics_dir / (t['id'] + '.md')}: '{m.group(0)}' is {what}")
        head, body = read_rows(topics_dir / f"{t['id']}.csv")
        out += [f"## {t['title']}", ""]
        if text:
            out += [text, ""]
        groups = t.get("group")
        if groups:
            g = head.index(groups["column"])
            for value, caption in groups["captions"].items():
                rows, total = current(head, [r for r in body if r[g] == value], t["key"])
                keep = [c for c in head if c != groups["column"]]
                idx = [head.index(c) for c in keep]
                out += [caption, ""]
                out += table(keep, [[r[i] for i in idx] for r in rows])
                out += ["", provenance(rows, total), ""]
        else:
            rows, total = current(head, body, t["key"])
            per_row = t.get("per_row", False)
            out += table(head, rows, per_row)
            if per_row:
                earlier = total - len(rows)
                out += [""] + ([f"{earlier} earlier row(s) in the CSV.", ""] if earlier else [])
            else:
                out += ["", provenance(rows, total), ""]
        notes = topics_dir / f"{t['id']}.notes.md"
        if notes.exists():
            note = notes.read_text().rstrip()
            for pattern, what in DATED:
                for m in pattern.finditer(note):
                    problems.append(f"{notes}: '{m.group(0)}' is {what}")
            out += [note, ""]
    return "\n".join(out).rstrip() + "\n", problems


def main():
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="compare, do not write")
    parser.add_argument("--dir", type=Path, default=DIR, help="the topics (docs/benchmarks)")
    parser.add_argument("--out", type=Path, default=OUT, help="the page (docs/BENCHMARKS.md)")
    args = parser.parse_args()
    text, problems = render(args.dir)
    if problems:
        print("\n".join(problems), file=sys.stderr)
        sys.exit(1)
    if args.check:
        if not args.out.exists() or args.out.read_text() != text:
            sys.exit(f"{args.out} is not what {args.dir} gives: run `make benchmarks`")
        return
    args.out.write_text(text)


if __name__ == "__main__":
    main()
