#!/usr/bin/python3
"""Replaces the README's headline block with the one `raylab report --md` wrote.

  /usr/bin/python3 scripts/update-readme-results.py README.md docs/results.md

The report marks its headline (the leaderboard of the first ray set and the provenance
line) with <!-- headline:begin --> / <!-- headline:end -->; the README holds the same
markers. Relative links of the report are rewritten relative to the README, and prose lines
are wrapped at 100 characters (the README keeps every line within 200; Markdown joins wrapped
lines again). Writes the README only when the block changed; exits 2 when a marker is missing.
"""
import os
import re
import sys
import textwrap

BEGIN, END = "<!-- headline:begin -->", "<!-- headline:end -->"


def block(text, name):
    i, j = text.find(BEGIN), text.find(END)
    if i < 0 or j < i:
        print(f"update-readme-results: {name}: no {BEGIN} ... {END} block", file=sys.stderr)
        sys.exit(2)
    return i, j


def wrap_prose(line):
    """A long prose line wrapped; table rows, images, headings and HTML stay as they are."""
    if len(line) <= 100 or line.lstrip().startswith(("|", "!", "#", "<", "`")):
        return line
    return "\n".join(textwrap.wrap(line, 100, break_long_words=False, break_on_hyphens=False))


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    readme_path, results_path = sys.argv[1:]
    readme, results = open(readme_path).read(), open(results_path).read()
    ri, rj = block(readme, readme_path)
    si, sj = block(results, results_path)
    headline = results[si + len(BEGIN):sj]
    rel = os.path.relpath(os.path.dirname(os.path.abspath(results_path)), os.path.dirname(os.path.abspath(readme_path)))
    headline = re.sub(r"\]\((?!https?:|/|#)([^)]+)\)", lambda m: f"]({os.path.join(rel, m.group(1))})", headline)
    headline = "\n".join(wrap_prose(line) for line in headline.split("\n"))
    new = readme[:ri + len(BEGIN)] + headline + readme[rj:]
    if new != readme:
        with open(readme_path + ".tmp", "w") as f:
            f.write(new)
        os.replace(readme_path + ".tmp", readme_path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
