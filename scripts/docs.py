#!/usr/bin/python3
"""The generated parts of raylab's documentation, and the check that keeps the docs honest.

  scripts/docs.py generate [--raylab build/raylab] [--root .]
      In every docs/structures/<name>.md, rewrites the block between
        <!-- params:begin --> and <!-- params:end -->   the structure's parameters and statistics,
                                                          from `raylab accels --json`;
        <!-- numbers:begin --> and <!-- numbers:end -->  the rows of docs/results.md's tables that
                                                          name the structure (or a spec of it),
                                                          with the run's provenance line.
      Writes a page only when it changed.

  scripts/docs.py check [--raylab build/raylab | --accels-json FILE] [--root .]
      Prints one line per problem and exits 1 when there is any (0 when there is none):
        - a relative link (or image) in README.md or docs/**/*.md that does not resolve,
          including its #anchor when it points into a Markdown file;
        - a registered structure without docs/structures/<name>.md, a page without one of the
          sections every structure page has, or without a README row linking to it;
        - a parameter that `raylab accels --json` lists and the page's generated block does not,
          or one the block lists and the registry no longer has (run `make docs-pages`);
        - README.md longer than 150 lines, a README line over 200 characters, `make demo` or
          `make test` not within README's first 40 lines;
        - wording that narrates the project's history (numbered work rounds, issue numbers)
          in README.md, CHANGELOG.md or docs/.
Exit 2 on bad arguments or when the registry cannot be read.
"""
import argparse
import json
import os
import re
import subprocess
import sys

README_MAX_LINES = 150
README_MAX_LINE_CHARS = 200
README_COMMANDS_WITHIN = 40
PARAMS = ("<!-- params:begin -->", "<!-- params:end -->")
NUMBERS = ("<!-- numbers:begin -->", "<!-- numbers:end -->")
# The sections of every structure page, in order (a heading starts with each).
SECTIONS = ("What it is", "How it is built and traversed", "Parameters", "Current numbers",
            "Where it fails", "What was tried")
# History narration has no place in the reference (it lives in git and CHANGELOG.md). The
# first word is spelled in two parts so that this file does not contain it.
HISTORY = re.compile(r"\b(sess" r"ions?|issues? #?\d+|round \d+ of)\b", re.IGNORECASE)


def registry(args):
    """The structures as `raylab accels --json` lists them."""
    try:
        if args.accels_json:
            with open(args.accels_json) as f:
                return json.load(f)
        out = subprocess.run([args.raylab, "accels", "--json"], check=True, capture_output=True, text=True)
        return json.loads(out.stdout)
    except (OSError, subprocess.CalledProcessError, json.JSONDecodeError) as e:
        print(f"docs.py: cannot read the registry: {e}", file=sys.stderr)
        sys.exit(2)


def replace_block(text, markers, body):
    """text with the part between the two markers replaced by body, or None without markers."""
    begin, end = markers
    i, j = text.find(begin), text.find(end)
    if i < 0 or j < i:
        return None
    return text[:i + len(begin)] + "\n" + body.rstrip("\n") + "\n" + text[j:]


def block(text, markers):
    begin, end = markers
    i, j = text.find(begin), text.find(end)
    return text[i + len(begin):j] if 0 <= i < j else None


def cell(s):
    return s.replace("|", "\\|").replace("\n", " ")


def params_block(info):
    lines = []
    params = info.get("params", [])
    if params:
        lines += ["| parameter | default | valid values | what it does |", "|---|---|---|---|"]
        for p in params:
            lines.append(f"| `{p['name']}` | `{cell(str(p['default']))}` | {cell(p.get('valid', ''))} | {cell(p['help'])} |")
    else:
        lines.append("No parameters.")
    stats = info.get("stats", [])
    if stats:
        lines += ["", "Statistics it reports besides the common ones (`extra` in the JSON reports, "
                  "[json-reports.md](../json-reports.md)):", "",
                  "| statistic | meaning |", "|---|---|"]
        lines += [f"| `{s['key']}` | {cell(s['help'])} |" for s in stats]
    lines += ["", "Generated from `raylab accels --json` by `make docs-pages` (scripts/docs.py)."]
    return "\n".join(lines)


def split_row(line):
    return [c.strip() for c in line.strip().strip("|").split("|")]


def plain(c):
    return c.replace("`", "").replace("*", "").strip()


def names_structure(c, name):
    c = plain(c)
    return c == name or c.startswith(name + ":")


def slug(heading):
    """GitHub's anchor for a heading."""
    s = heading.strip().lower()
    s = re.sub(r"[^\w\- ]", "", s)
    return s.replace(" ", "-")


def results_tables(text):
    """(heading, caption, header lines, rows) for every table of a Markdown text; the caption is
    the alt text of an image right above the table (the report puts each table under its chart)."""
    heading, caption, tables, lines = "", "", [], text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("#"):
            heading, caption = line.lstrip("#").strip(), ""
        elif re.match(r"^!\[[^\]]+\]", line):
            caption = re.match(r"^!\[([^\]]+)\]", line).group(1)
        if line.startswith("|") and i + 1 < len(lines) and re.match(r"^\|[\s:|-]+\|\s*$", lines[i + 1]):
            j = i + 2
            rows = []
            while j < len(lines) and lines[j].startswith("|"):
                rows.append(lines[j])
                j += 1
            tables.append((heading, caption, lines[i:i + 2], rows))
            caption = ""
            i = j
            continue
        i += 1
    return tables


def numbers_block(name, results_text, all_names, max_rows=12):
    if results_text is None:
        return ("docs/results.md does not exist yet: `make docs` writes it from the study, "
                "and this block with it.")
    out = []
    tables = results_tables(results_text)
    per_heading = {}
    for t in tables:
        per_heading[t[0]] = per_heading.get(t[0], 0) + 1
    for heading, caption, header, rows in tables:
        if per_heading[heading] == 1:
            caption = ""  # one table in its section: the section's heading names it
        first_is_structure = any(plain(split_row(r)[0]).split(":")[0] in all_names for r in rows)
        columns = [i for i, c in enumerate(split_row(header[0])) if i > 0 and names_structure(c, name)]
        if first_is_structure:
            mine = [r for r in rows if names_structure(split_row(r)[0], name)]
        elif columns:
            # The structures are the columns (a table per class or scene): its column beside the first.
            keep = [0] + columns
            pick = lambda line: "| " + " | ".join(split_row(line)[i] for i in keep) + " |"
            header, mine = [pick(header[0]), pick(header[1])], [pick(r) for r in rows]
        else:
            mine = [r for r in rows if any(names_structure(c, name) or re.search(rf"`{re.escape(name)}[`:]", c)
                                           for c in split_row(r))]
        if not mine:
            continue
        title = caption or heading or "docs/results.md"
        out.append(f"**[{title}](../results.md#{slug(heading)})**" if heading else f"**{title}**")
        out.append("")
        out += header + mine[:max_rows]
        if len(mine) > max_rows:
            out.append("")
            out.append(f"({len(mine) - max_rows} more rows in [results.md](../results.md#{slug(heading)}).)")
        out.append("")
    provenance = [l for l in results_text.splitlines() if l.startswith("Machine:")]
    if not out:
        out.append("The last study's tables ([results.md](../results.md)) do not name this structure.")
        out.append("")
    if provenance:
        out.append(provenance[-1])
        out.append("")
    out.append("Excerpt of [docs/results.md](../results.md), written by `make docs` (scripts/docs.py).")
    return "\n".join(out)


def structure_page(root, name):
    return os.path.join(root, "docs", "structures", name + ".md")


def generate(args):
    accels = registry(args)
    names = {a["name"] for a in accels}
    results_path = os.path.join(args.root, "docs", "results.md")
    results_text = open(results_path).read() if os.path.exists(results_path) else None
    status = 0
    for info in accels:
        path = structure_page(args.root, info["name"])
        if not os.path.exists(path):
            print(f"docs.py: {os.path.relpath(path, args.root)} is missing: write the page first "
                  f"(the sections: {', '.join(SECTIONS)})", file=sys.stderr)
            status = 1
            continue
        text = open(path).read()
        new = replace_block(text, PARAMS, params_block(info))
        new = new and replace_block(new, NUMBERS, numbers_block(info["name"], results_text, names))
        if new is None:
            print(f"docs.py: {os.path.relpath(path, args.root)}: no {PARAMS[0]} or {NUMBERS[0]} block",
                  file=sys.stderr)
            status = 1
        elif new != text:
            with open(path + ".tmp", "w") as f:
                f.write(new)
            os.replace(path + ".tmp", path)
    return status


# ---- check ----

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)|<img\s[^>]*src=\"([^\"]+)\"")


def prose_lines(text):
    """(line number, line) outside fenced code blocks, with inline code spans removed."""
    fenced = False
    for n, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if not fenced:
            yield n, re.sub(r"`[^`]*`", "", line)


def anchors(path, cache={}):
    if path not in cache:
        seen, found = {}, set()
        for _, line in prose_lines(open(path).read()):
            m = re.match(r"^#{1,6}\s+(.*)$", line)
            if m:
                s = slug(m.group(1))
                k = seen.get(s, 0)
                found.add(s if k == 0 else f"{s}-{k}")
                seen[s] = k + 1
        cache[path] = found
    return cache[path]


def check_links(root, md, problems):
    text = open(md).read()
    rel = os.path.relpath(md, root)
    for n, line in prose_lines(text):
        for m in LINK.finditer(line):
            target = m.group(1) or m.group(2)
            if re.match(r"^[a-z]+:", target):
                continue
            path, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(md), path)) if path else md
            if not os.path.exists(dest):
                problems.append(f"{rel}:{n}: link to {target}: {os.path.relpath(dest, root)} does not exist")
            elif anchor and dest.endswith(".md") and anchor not in anchors(dest):
                problems.append(f"{rel}:{n}: link to {target}: no heading with anchor #{anchor} in "
                                f"{os.path.relpath(dest, root)}")


def markdown_files(root):
    files = [os.path.join(root, "README.md")]
    for d, _, names in os.walk(os.path.join(root, "docs")):
        files += [os.path.join(d, f) for f in sorted(names) if f.endswith(".md")]
    return files


def check(args):
    accels = registry(args)
    root = args.root
    problems = []
    readme_path = os.path.join(root, "README.md")
    if not os.path.exists(readme_path):
        print("README.md: missing")
        return 1
    readme = open(readme_path).read().splitlines()
    if len(readme) > README_MAX_LINES:
        problems.append(f"README.md: {len(readme)} lines, more than {README_MAX_LINES}")
    for n, line in enumerate(readme, 1):
        if len(line) > README_MAX_LINE_CHARS:
            problems.append(f"README.md:{n}: {len(line)} characters, more than {README_MAX_LINE_CHARS}")
    head = "\n".join(readme[:README_COMMANDS_WITHIN])
    for command in ("make demo", "make test"):
        if command not in head:
            problems.append(f"README.md: `{command}` is not within its first {README_COMMANDS_WITHIN} lines")

    files = markdown_files(root)
    for md in files:
        check_links(root, md, problems)
    for md in files + [os.path.join(root, "CHANGELOG.md")]:
        if not os.path.exists(md):
            continue
        for n, line in enumerate(open(md).read().splitlines(), 1):
            m = HISTORY.search(line)
            if m:
                problems.append(f"{os.path.relpath(md, root)}:{n}: '{m.group(0)}' narrates the project's history; "
                                "say what the code does and why (history lives in git and CHANGELOG.md)")

    readme_text = "\n".join(readme)
    for info in accels:
        name = info["name"]
        page = structure_page(root, name)
        rel = os.path.relpath(page, root)
        if f"(docs/structures/{name}.md)" not in readme_text:
            problems.append(f"README.md: no row linking {name}'s page docs/structures/{name}.md")
        if not os.path.exists(page):
            problems.append(f"{rel}: missing: every registered structure has its page")
            continue
        text = open(page).read()
        headings = [l[3:].strip() for _, l in prose_lines(text) if l.startswith("## ")]
        for section in SECTIONS:
            if not any(h.startswith(section) for h in headings):
                problems.append(f"{rel}: no section '## {section}...'")
        listed = block(text, PARAMS)
        if listed is None:
            problems.append(f"{rel}: no {PARAMS[0]} ... {PARAMS[1]} block")
            continue
        if block(text, NUMBERS) is None:
            problems.append(f"{rel}: no {NUMBERS[0]} ... {NUMBERS[1]} block")
        in_block = set(re.findall(r"^\| `([^`]+)` \| `", listed, re.MULTILINE))
        registered = {p["name"] for p in info.get("params", [])}
        for p in sorted(registered - in_block):
            problems.append(f"{rel}: parameter '{p}' of `raylab accels --json` is not in the page's "
                            "parameter block (run `make docs-pages`)")
        for p in sorted(in_block - registered):
            problems.append(f"{rel}: parameter '{p}' is in the page's parameter block but no longer "
                            "in the registry (run `make docs-pages`)")
    for p in problems:
        print(p)
    if problems:
        print(f"docs check: {len(problems)} problem(s)")
        return 1
    print(f"docs check: README ({len(readme)} lines), {len(files)} Markdown files, "
          f"{len(accels)} structure pages: ok")
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("command", choices=["generate", "check"])
    ap.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    ap.add_argument("--raylab", default="build/raylab")
    ap.add_argument("--accels-json", help="the registry as a file (instead of running raylab)")
    args = ap.parse_args()
    args.root = os.path.abspath(args.root)
    return generate(args) if args.command == "generate" else check(args)


if __name__ == "__main__":
    sys.exit(main())
