#!/usr/bin/env python3
"""The documents hold together.

  check_docs.py SOURCE_ROOT BINARY

- README.md is at most 250 lines and links every docs/*.md;
- every relative link in README.md and docs/*.md names a file that exists, and
  every #anchor a heading of that file;
- the man page (docs/shadowbench.1) names every command and long option that
  `shadowbench --help` lists."""
import glob
import os
import re
import subprocess
import sys


def anchor(heading):
    a = heading.strip().lower()
    a = re.sub(r"[^\w\- ]", "", a)
    return a.replace(" ", "-")


def main():
    root, binary = sys.argv[1], sys.argv[2]
    problems, checks = [], 0
    readme = open(os.path.join(root, "README.md"), encoding="utf-8").read()
    checks += 1
    if readme.count("\n") > 250:
        problems.append(f"README.md has {readme.count(chr(10))} lines, more than 250")
    for doc in sorted(glob.glob(os.path.join(root, "docs", "*.md"))):
        checks += 1
        rel = os.path.relpath(doc, root)
        if f"({rel})" not in readme:
            problems.append(f"README.md does not link {rel}")
    for path in [os.path.join(root, "README.md")] + sorted(glob.glob(os.path.join(root, "docs", "*.md"))):
        text = open(path, encoding="utf-8").read()
        for m in re.finditer(r"\]\(([^)\s]+)\)", text):
            target = m.group(1)
            if re.match(r"[a-z]+:", target):
                continue
            checks += 1
            file, _, frag = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(path), file)) if file else path
            where = f"{os.path.relpath(path, root)}: link ({target})"
            if not os.path.exists(dest):
                problems.append(f"{where}: no such file")
                continue
            if frag and dest.endswith(".md"):
                heads = {anchor(h) for h in re.findall(r"^#+ (.*)$", open(dest, encoding="utf-8").read(), re.M)}
                if frag not in heads:
                    problems.append(f"{where}: no heading #{frag} in {os.path.relpath(dest, root)}")
    man = open(os.path.join(root, "docs", "shadowbench.1"), encoding="utf-8").read().replace("\\-", "-")
    help_text = subprocess.run([binary, "--help"], capture_output=True, text=True).stdout
    names = set(re.findall(r"(--[a-z][a-z-]+)", help_text)) | set(re.findall(r"shadowbench ([a-z]+)", help_text))
    for n in sorted(names):
        checks += 1
        if n not in man:
            problems.append(f"docs/shadowbench.1 does not name {n} (shadowbench --help does)")
    for p in problems:
        print(p)
    print(f"{checks - len(problems)} passed, {len(problems)} failed")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
