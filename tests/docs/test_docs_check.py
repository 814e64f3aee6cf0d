#!/usr/bin/python3
"""The docs check (scripts/docs.py) on a small fixture tree: intact it must pass, and broken one
way per case it must fail with a message naming the problem.

  tests/docs/test_docs_check.py CASE      (ctest runs one DocsCheck.Fixture<CASE> per case)

The fixture is written to a temporary directory: a README, two pages, one registered structure
`alpha` with parameters `p1` and `p2`, and a results page whose tables name it. Its generated
blocks come from `docs.py generate`, so the intact case also checks the generator's output.
"""
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
DOCS_PY = os.path.join(HERE, "..", "..", "scripts", "docs.py")

REGISTRY = [{
    "name": "alpha", "help": "a structure",
    "params": [{"name": "p1", "default": "1", "valid": "0 or 1", "help": "first"},
               {"name": "p2", "default": "auto", "valid": "auto or >= 1", "help": "second | with a bar"}],
    "stats": [{"key": "cells", "help": "cells built"}],
}]

README = """# fixture

What it answers. Start with `make demo` and `make test`.

| structure | what it is | page |
|---|---|---|
| `alpha` | a structure | [alpha](docs/structures/alpha.md) |

See [the method](docs/method.md#the-oracle) and ![a picture](docs/pic.png).
"""

PAGE = """# `alpha`

## What it is

A structure.

## How it is built and traversed here

By hand. See [method](../method.md).

## Parameters

<!-- params:begin -->
<!-- params:end -->

## Current numbers

<!-- numbers:begin -->
<!-- numbers:end -->

## Where it fails, and why

Nowhere.

## What was tried and not kept

| what | measured effect | why not kept |
|---|---|---|
"""

METHOD = """# Method

## The oracle

Exact. Back to the [README](../README.md).
"""

RESULTS = """# report

## Leaderboard

![primary rays](x.svg)

| structure | ratio to Embree |
|---|---:|
| embree | 1.00 |
| alpha | 0.50 |
| alpha:p1=0 | 0.25 |

## Per class

| class | `embree` | `alpha` |
|---|---:|---:|
| interiors | 1.00 | 0.40 |

Machine: a test machine. Revision of the binary: abc1234.
"""


def write(root, rel, text):
    path = os.path.join(root, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)


def read(root, rel):
    with open(os.path.join(root, rel)) as f:
        return f.read()


def docs_py(root, command, registry):
    reg = os.path.join(root, "..", "registry.json")
    with open(reg, "w") as f:
        json.dump(registry, f)
    return subprocess.run([sys.executable, DOCS_PY, command, "--root", root, "--accels-json", reg],
                          capture_output=True, text=True)


def fixture(root):
    write(root, "README.md", README)
    write(root, "docs/structures/alpha.md", PAGE)
    write(root, "docs/method.md", METHOD)
    write(root, "docs/results.md", RESULTS)
    write(root, "docs/pic.png", "not really a png")
    write(root, "docs/x.svg", "<svg/>")
    write(root, "docs/json-reports.md", "# JSON reports\n")
    r = docs_py(root, "generate", REGISTRY)
    assert r.returncode == 0, r.stdout + r.stderr


def edit(root, rel, old, new):
    text = read(root, rel)
    assert old in text, f"fixture: {old!r} not in {rel}"
    write(root, rel, text.replace(old, new, 1))


def without_param(name):
    reg = json.loads(json.dumps(REGISTRY))
    reg[0]["params"] = [p for p in reg[0]["params"] if p["name"] != name]
    return reg


def with_param(name):
    reg = json.loads(json.dumps(REGISTRY))
    reg[0]["params"].append({"name": name, "default": "0", "valid": "0 or 1", "help": "new"})
    return reg


# case: (how to break the fixture, registry to check against, what the message must say)
CASES = {
    "BrokenLink": (lambda r: edit(r, "docs/method.md", "Exact.", "Exact, see [x](missing.md)."),
                   REGISTRY, "missing.md does not exist"),
    "BrokenImage": (lambda r: os.remove(os.path.join(r, "docs/pic.png")), REGISTRY, "docs/pic.png does not exist"),
    "BrokenAnchor": (lambda r: edit(r, "README.md", "#the-oracle", "#no-such-heading"),
                     REGISTRY, "no heading with anchor #no-such-heading"),
    "MissingPage": (lambda r: os.remove(os.path.join(r, "docs/structures/alpha.md")),
                    REGISTRY, "every registered structure has its page"),
    "MissingSection": (lambda r: edit(r, "docs/structures/alpha.md", "## Where it fails, and why", "## Limits"),
                       REGISTRY, "no section '## Where it fails"),
    "MissingParameter": (lambda r: None, with_param("p3"), "parameter 'p3' of `raylab accels --json` is not in"),
    "StaleParameter": (lambda r: None, without_param("p2"), "parameter 'p2' is in the page's parameter block but no longer"),
    "MissingReadmeRow": (lambda r: edit(r, "README.md", "| `alpha` | a structure | [alpha](docs/structures/alpha.md) |\n", ""),
                         REGISTRY, "no row linking alpha's page"),
    "ReadmeTooLong": (lambda r: edit(r, "README.md", "What it answers.", "What it answers.\n" + "line\n" * 150),
                      REGISTRY, "lines, more than 150"),
    "ReadmeLineTooLong": (lambda r: edit(r, "README.md", "What it answers.", "What it answers " + "x" * 190 + "."),
                          REGISTRY, "characters, more than 200"),
    "MakeDemoLate": (lambda r: edit(r, "README.md", "Start with `make demo` and `make test`.",
                                    "Start below.\n" + "\n" * 40 + "`make demo` and `make test`."),
                     REGISTRY, "`make demo` is not within its first 40 lines"),
    "HistoryWording": (lambda r: edit(r, "docs/method.md", "Exact.", "Exact since se" + "ssion 4."),
                       REGISTRY, "narrates the project's history"),
}


def main():
    if len(sys.argv) != 2 or sys.argv[1] not in ["Intact"] + list(CASES):
        print(f"usage: {sys.argv[0]} Intact|{'|'.join(CASES)}", file=sys.stderr)
        return 2
    case = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        root = os.path.join(tmp, "repo")
        fixture(root)
        if case == "Intact":
            page = read(root, "docs/structures/alpha.md")
            for expected in ("| `p1` | `1` | 0 or 1 | first |", "| `p2` | `auto` | auto or >= 1 | second \\| with a bar |",
                             "| `cells` | cells built |", "| alpha | 0.50 |", "| alpha:p1=0 | 0.25 |",
                             "| interiors | 0.40 |", "Revision of the binary: abc1234"):
                if expected not in page:
                    print(f"FAIL: the generated page lacks {expected!r}:\n{page}")
                    return 1
            if "| embree | 1.00 |" in page:
                print(f"FAIL: the numbers block took another structure's row:\n{page}")
                return 1
            r = docs_py(root, "check", REGISTRY)
            if r.returncode != 0:
                print(f"FAIL: the intact fixture fails the check (exit {r.returncode}):\n{r.stdout}{r.stderr}")
                return 1
            print("ok: the intact fixture passes;", r.stdout.strip())
            return 0
        breaker, registry, message = CASES[case]
        breaker(root)
        r = docs_py(root, "check", registry)
        if r.returncode != 1 or message not in r.stdout:
            print(f"FAIL: {case}: expected exit 1 with {message!r}, got exit {r.returncode}:\n{r.stdout}{r.stderr}")
            return 1
        print(f"ok: {case} fails the check:", r.stdout.strip().splitlines()[0])
        return 0


if __name__ == "__main__":
    sys.exit(main())
