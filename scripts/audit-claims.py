#!/usr/bin/env python3
"""Breaks the product on purpose and reports which tests notice: the check behind docs/claims.md.

Each breakage in the list (scripts/breakages.toml) names its edits to product code, each a
snippet found exactly once under crates/*/src (searched, so a file may move) and its
replacement, and the tests that hold the claim. The script copies the working tree (tracked and
untracked files, not target/) to a scratch folder, runs the tests there unbroken once, then for
each breakage applies its edits, runs its tests and puts the files back. It prints a markdown
table (breakage, where the snippet was, the tests, which failed and the first line of the
failure) and writes it to --out.

    python3 scripts/audit-claims.py [--list FILE] [--only TEXT]... [--out FILE] [--timeout S]
                                    [--target-dir DIR] [--no-baseline]

The builds share target/ with the working tree unless --target-dir says otherwise (a copy of it
lets the tree build meanwhile): the dependencies are reused, the scratch copy's own crates build
beside the tree's (another path, other artefacts). Each breakage rebuilds what
depends on its crate: minutes each on a 2-core machine.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SOURCES = ("*.rs", "*.wgsl")


def copy_tree(scratch: Path) -> None:
    """The working tree's tracked and untracked (not ignored) files, as they are now."""
    files = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT, check=True, capture_output=True).stdout.decode().split("\0")
    for name in filter(None, files):
        source = ROOT / name
        if source.is_file():
            target = scratch / name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target)


def find_snippet(scratch: Path, snippet: str) -> tuple[list[Path], int]:
    """The files under crates/*/src holding `snippet`, and how often it occurs in all."""
    found, count = [], 0
    for pattern in SOURCES:
        for path in sorted(scratch.glob(f"crates/*/src/**/{pattern}")):
            n = path.read_text().count(snippet)
            if n:
                found.append(path)
                count += n
    return found, count


def run_tests(scratch: Path, package: str, target: str, tests: list[str], args):
    """(status, failed tests, first failure line): status is passed, failed, no build or timeout."""
    command = ["cargo", "test", "--release", "-p", package, "--test", target, "--", *tests]
    env = {"CARGO_TARGET_DIR": args.target_dir, "RUST_BACKTRACE": "0"}
    timeout = args.timeout
    try:
        run = subprocess.run(command, cwd=scratch, capture_output=True, text=True,
                             timeout=timeout, env={**os.environ, **env})
    except subprocess.TimeoutExpired:
        return "timeout", [], f"over {timeout} s"
    output = run.stdout + run.stderr
    if "could not compile" in output:
        error = next((l for l in output.splitlines() if l.startswith("error")), "")
        return "no build", [], error
    failed = re.findall(r"^test (\S+) \.\.\. FAILED$", output, re.M)
    ran = re.findall(r"^test (\S+) \.\.\. (?:ok|FAILED)$", output, re.M)
    if run.returncode == 0:
        return ("passed" if ran else "no test ran"), [], ""
    return "failed", failed, first_failure(output)


def first_failure(output: str) -> str:
    """The first panic's message up to its first blank line (an assertion's left and right
    too), shortened."""
    lines = output.splitlines()
    for i, line in enumerate(lines):
        if "panicked at" in line:
            message = []
            for text in lines[i + 1:]:
                if not text.strip() or text.startswith("note:"):
                    break
                message.append(text.strip())
            # the scratch folders' names change from run to run
            message = " ".join(message).replace(tempfile.gettempdir() + "/", "$TMP/")
            return message if len(message) <= 300 else message[:297] + "..."
    return next((l for l in lines if l.startswith("error")), "")


def cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--list", default=str(ROOT / "scripts/breakages.toml"))
    parser.add_argument("--only", action="append", default=[],
                        help="only the breakages whose name holds this text (repeatable)")
    parser.add_argument("--out", help="also write the table here")
    parser.add_argument("--timeout", type=int, default=1800, help="seconds a test run may take")
    parser.add_argument("--no-baseline", action="store_true",
                        help="skip the unbroken run of the tests")
    parser.add_argument("--target-dir", default=str(ROOT / "target"),
                        help="cargo's target folder (default the tree's: its dependencies reused)")
    args = parser.parse_args()
    breakages = tomllib.loads(Path(args.list).read_text())["breakage"]
    if args.only:
        breakages = [b for b in breakages if any(o in b["name"] for o in args.only)]
    scratch = Path(tempfile.mkdtemp(prefix="quadray-audit-"))
    rows = []
    try:
        copy_tree(scratch)
        groups = {}
        for b in breakages:
            groups.setdefault((b["package"], b["target"]), []).extend(b["tests"])
        for (package, target), tests in ({} if args.no_baseline else groups).items():
            status, failed, message = run_tests(scratch, package, target, tests, args)
            print(f"unbroken {package} {target}: {status} {failed} {message}", file=sys.stderr)
            if status != "passed":
                rows.append(("(unbroken)", "", f"`{package}` {target}: {', '.join(tests)}",
                             f"{status}: {', '.join(failed)}", message))
        for b in breakages:
            started = time.monotonic()
            originals, places, problem = {}, [], ""
            for edit in b["edit"]:
                files, count = find_snippet(scratch, edit["snippet"])
                if count != 1:
                    problem = f"snippet found {count} times: {edit['snippet'][:60]!r}"
                    break
                path = files[0]
                originals.setdefault(path, path.read_text())
                path.write_text(path.read_text().replace(edit["snippet"], edit["replacement"]))
                places.append(str(path.relative_to(scratch)))
            if problem:
                result, failed, message = "not applied", [], problem
            else:
                result, failed, message = run_tests(
                    scratch, b["package"], b["target"], b["tests"], args)
            for path, text in originals.items():
                path.write_text(text)
            held = result in ("failed", "no build")
            verdict = (f"fails: {', '.join(failed)}" if result == "failed"
                       else result if held else f"**{result}**")
            rows.append((b["name"], ", ".join(f"`{p}`" for p in places),
                         ", ".join(f"`{t}`" for t in b["tests"]), verdict, message))
            print(f"{b['name']}: {verdict} ({time.monotonic() - started:.0f} s) {message}",
                  file=sys.stderr)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    table = ["| breakage | product code | tests | result | first failure |",
             "|---|---|---|---|---|"]
    table += ["| " + " | ".join(cell(c) for c in row) + " |" for row in rows]
    text = "\n".join(table) + "\n"
    print(text)
    if args.out:
        Path(args.out).write_text(text)
    return 0 if all(not r[3].startswith("**") for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
