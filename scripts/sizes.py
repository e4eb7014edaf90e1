#!/usr/bin/env python3
"""List Rust source files over a line budget and functions over a line budget.

Usage: scripts/sizes.py [--file-max N] [--fn-max N] [ROOT ...]

A file counts all its lines, in-file `#[cfg(test)] mod tests` included.
A function counts from the line of its `fn` keyword to the line of its closing brace
(signature, where-clause and body; not its doc comment or attributes).
By default it scans src/ without the front ends (src/app, src/cli.rs, src/cli/, src/edges,
src/bin), the part the size budget applies to.
Prints one line per offender and exits 1 if there is any, so it can gate a check.
"""

import os
import re
import sys

SKIP = ("src/app/", "src/cli.rs", "src/cli/", "src/edges/", "src/bin/")
FN = re.compile(r"\bfn\s+([A-Za-z_][A-Za-z0-9_]*)")


def blank_code(text):
    """The text with comments, strings and char literals replaced by spaces (newlines kept),
    so that braces and `fn` inside them are not seen."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:]) and not (i and (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'r(#*)"', text[i:])
            close = '"' + m.group(1)
            j = text.find(close, i + len(m.group(0)))
            j = n if j < 0 else j + len(close)
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "'":
            # A char literal ('a', '\n', '\u{..}', '{') or a lifetime ('a).
            m = re.match(r"'(\\u\{[0-9a-fA-F]+\}|\\.|[^\\'])'", text[i:])
            if m:
                out.append(" " * len(m.group(0)))
                i += len(m.group(0))
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def long_fns(code, fn_max):
    """(line, name, length) of each function longer than fn_max lines."""
    found = []
    for m in FN.finditer(code):
        # The body opens at the first `{` not inside parentheses, brackets or angle brackets of
        # the signature; a `;` first means a declaration without body (trait method).
        depth, j = 0, m.end()
        while j < len(code):
            ch = code[j]
            if ch in "([":
                depth += 1
            elif ch in ")]":
                depth -= 1
            elif ch == ";" and depth == 0:
                j = -1
                break
            elif ch == "{" and depth == 0:
                break
            j += 1
        if j < 0 or j >= len(code):
            continue
        braces, k = 0, j
        while k < len(code):
            if code[k] == "{":
                braces += 1
            elif code[k] == "}":
                braces -= 1
                if braces == 0:
                    break
            k += 1
        first = code.count("\n", 0, m.start()) + 1
        last = code.count("\n", 0, k) + 1
        if last - first + 1 > fn_max:
            found.append((first, m.group(1), last - first + 1))
    return found


def main(argv):
    file_max, fn_max, roots = 700, 150, []
    it = iter(argv)
    for a in it:
        if a == "--file-max":
            file_max = int(next(it))
        elif a == "--fn-max":
            fn_max = int(next(it))
        else:
            roots.append(a)
    roots = roots or ["src"]
    bad = 0
    for root in roots:
        for dirpath, _, files in sorted(os.walk(root)):
            for f in sorted(files):
                if not f.endswith(".rs"):
                    continue
                path = os.path.join(dirpath, f)
                rel = path.replace(os.sep, "/")
                if any(rel.startswith(s) or ("/" + s) in rel for s in SKIP):
                    continue
                text = open(path, encoding="utf-8").read()
                lines = text.count("\n") + (0 if text.endswith("\n") else 1)
                if lines > file_max:
                    print(f"{rel}: {lines} lines")
                    bad += 1
                for line, name, length in long_fns(blank_code(text), fn_max):
                    print(f"{rel}:{line}: fn {name}: {length} lines")
                    bad += 1
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
