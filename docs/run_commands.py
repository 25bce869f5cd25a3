#!/usr/bin/env python3
"""Run every command of the user guide, as CI does (docs/getting-started.md, "Building
this guide").

Every fenced block whose info string is `sh` in README.md and docs/*.md is run with
`bash -euo pipefail` from the repository's root, in the order of the files below and of the
blocks in each file; a block that exits non-zero (or runs past --timeout) fails the run
(exit 1) after every block has been tried. Blocks labelled otherwise (`text`, `toml`,
`python`, `bash` for a file's contents such as a Slurm batch script) are not commands.

Two exceptions, each printed when it applies: `cargo test --release` lines are left out
(CI runs that command itself, first), and with --no-hdf5 the blocks that ask for
`--features hdf5` are skipped (CI's machine without libhdf5).

    python3 docs/run_commands.py [--no-hdf5] [--list] [--timeout SECONDS]
"""

import argparse
import pathlib
import re
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent


def files():
    yield ROOT / "README.md"
    yield from sorted((ROOT / "docs").glob("*.md"))
    yield from sorted((ROOT / "docs" / "gallery").glob("*.md"))


def blocks(path):
    """The `sh` blocks of one Markdown file: (first line number, text)."""
    out, current, start, fence = [], None, 0, None
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        stripped = line.strip()
        if fence is None:
            m = re.match(r"^(`{3,}|~{3,})\s*([\w-]*)", stripped)
            if m:
                fence = m.group(1)
                current = [] if m.group(2) == "sh" else None
                start = number + 1
        elif stripped.startswith(fence) and stripped.strip("`~") == "":
            if current is not None:
                out.append((start, "\n".join(current)))
            fence, current = None, None
        elif current is not None:
            current.append(line)
    if fence is not None:
        raise SystemExit(f"{path}: a code fence opened at line {start - 1} is never closed")
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--no-hdf5", action="store_true", help="skip blocks that need --features hdf5")
    parser.add_argument("--list", action="store_true", help="print the blocks, run nothing")
    parser.add_argument("--timeout", type=float, default=1200.0, help="seconds per block (default 1200)")
    args = parser.parse_args()

    seen, todo = set(), []
    for path in files():
        for line, text in blocks(path):
            kept = []
            for cmd in text.split("\n"):
                if cmd.split("#")[0].strip() == "cargo test --release":
                    print(f"{path.relative_to(ROOT)}:{line}: `cargo test --release` left out (CI runs it first)")
                    continue
                kept.append(cmd)
            text = "\n".join(kept).strip()
            if not text or text in seen:
                continue
            seen.add(text)
            todo.append((f"{path.relative_to(ROOT)}:{line}", text))

    failed, total = [], time.monotonic()
    for where, text in todo:
        if args.no_hdf5 and "--features hdf5" in text:
            print(f"{where}: skipped (needs the hdf5 feature; --no-hdf5)")
            continue
        print(f"\n== {where}\n{text}", flush=True)
        if args.list:
            continue
        start = time.monotonic()
        try:
            rc = subprocess.run(["bash", "-euo", "pipefail", "-c", text], cwd=ROOT,
                                timeout=args.timeout).returncode
        except subprocess.TimeoutExpired:
            rc = f"timed out after {args.timeout:.0f} s"
        took = time.monotonic() - start
        print(f"-- {where}: exit {rc} in {took:.1f} s", flush=True)
        if rc != 0:
            failed.append(f"{where} (exit {rc})")
    print(f"\n{len(todo)} blocks in {time.monotonic() - total:.0f} s")
    if failed:
        print("failed:\n  " + "\n  ".join(failed), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
