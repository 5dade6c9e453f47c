#!/usr/bin/env python3
"""layout-checks: the source tree's shape, measured, for a maintainer or a
reviewer to read (not a test: none of it is a property of what the
toolchain computes).

It prints, for the Rust sources of src/ and crates/*/src (test modules
left out):
- import cycles between files: each file's `use`, `crate::` and `super::`
  paths resolved to the file that defines them (a module's `mod` lines do
  not count as imports);
- the files of src/ over 1,000 lines;
- the functions over 100 lines (signature to closing brace, comments and
  strings stripped);
- the uses of `Variant::Lowres`, `#[doc(hidden)]` and
  `allow(clippy::too_many_arguments)`.

Run from the repository root: python3 scripts/layout-checks.py
A small scanner written here: no Rust parser ships with Python, and the
checks need only paths and brace depth.
"""

import os
import re
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))


def strip(text):
    """The code of `text` without comments, strings and char literals."""
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r'(?<![A-Za-z0-9_])r(#*)"(?:.|\n)*?"\1', '""', text)
    text = re.sub(r'"(?:\\.|[^"\\])*"', '""', text)
    text = re.sub(r"'(?:\\.|[^'\\])'", "' '", text)
    return text


def without_tests(text):
    """`text` without its `#[cfg(test)] mod name { ... }` bodies."""
    pattern = re.compile(r"#\[cfg\(test\)\]\s*(pub(\([^)]*\))?\s+)?mod\s+\w+\s*\{")
    out, i = [], 0
    while True:
        m = pattern.search(text, i)
        if not m:
            out.append(text[i:])
            return "".join(out)
        out.append(text[i : m.start()])
        depth, j = 0, m.end() - 1
        while j < len(text):
            if text[j] == "{":
                depth += 1
            elif text[j] == "}":
                depth -= 1
                if depth == 0:
                    break
            j += 1
        i = j + 1


def sources():
    """(crate source root, file) of every Rust source outside tests."""
    roots = ["src"] + [
        os.path.join("crates", c, "src")
        for c in sorted(os.listdir(os.path.join(ROOT, "crates")))
        if os.path.isdir(os.path.join(ROOT, "crates", c, "src"))
    ]
    for base in roots:
        for folder, _, files in os.walk(os.path.join(ROOT, base)):
            if os.path.relpath(folder, ROOT).startswith(os.path.join("src", "tests")):
                continue
            for name in sorted(files):
                if name.endswith(".rs"):
                    yield base, os.path.join(folder, name)


def module_path(base, path):
    parts = os.path.relpath(path, os.path.join(ROOT, base))[:-3].split(os.sep)
    return parts[:-1] if parts[-1] in ("mod", "lib", "main") else parts


def expand(tree):
    """The paths a `use` tree names."""
    tree = tree.strip()
    m = re.match(r"^([\w:]*?)(::)?\{(.*)\}$", tree, re.S)
    if not m:
        return [re.sub(r"\s+as\s+\w+$", "", tree)]
    prefix, inner, parts, depth, current = m.group(1), m.group(3), [], 0, ""
    for c in inner:
        depth += c == "{"
        depth -= c == "}"
        if c == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += c
    parts.append(current)
    return [
        (prefix + "::" + e) if prefix else e
        for p in parts
        if p.strip()
        for e in expand(p)
    ]


def cycles(files):
    known = {path for _, path in files}

    def resolve(base, segments):
        for n in range(len(segments), 0, -1):
            stem = os.path.join(ROOT, base, *segments[:n])
            for candidate in (stem + ".rs", os.path.join(stem, "mod.rs")):
                if candidate in known:
                    return candidate
        return None

    edges = {}
    for base, path in files:
        code = without_tests(strip(open(path).read()))
        here = module_path(base, path)
        paths = [e for m in re.finditer(r"\buse\s+([^;]+);", code) for e in expand(m.group(1))]
        paths += re.findall(r"\b((?:crate|super|self)(?:::\w+)+)", code)
        targets = set()
        for p in paths:
            segments = [s for s in p.replace(" ", "").split("::") if s]
            if not segments or segments[0] not in ("crate", "super", "self"):
                continue
            current = [] if segments[0] == "crate" else list(here)
            if segments[0] == "crate":
                segments = segments[1:]
            while segments and segments[0] in ("super", "self"):
                if segments[0] == "super":
                    current = current[:-1]
                segments = segments[1:]
            target = resolve(base, current + segments)
            if target and target != path:
                targets.add(target)
        edges[path] = targets
    # Tarjan's strongly connected components.
    index, low, stack, on, found, counter = {}, {}, [], set(), [], [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(os.path.relpath(c, ROOT) for c in component))

    for v in edges:
        if v not in index:
            visit(v)
    return found


def long_functions(files, limit=100):
    out = []
    for _, path in files:
        lines = without_tests(strip(open(path).read())).split("\n")
        for k, line in enumerate(lines):
            m = re.match(r"\s*(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?fn\s+(\w+)", line)
            if not m:
                continue
            depth, opened, end = 0, False, None
            for kk in range(k, len(lines)):
                for c in lines[kk]:
                    if c == "{":
                        depth += 1
                        opened = True
                    elif c == "}":
                        depth -= 1
                    elif c == ";" and not opened and depth == 0:
                        end = -1
                        break
                if end == -1 or (opened and depth == 0):
                    end = kk if end is None else end
                    break
            if end is not None and end >= 0 and end - k + 1 > limit:
                out.append((end - k + 1, os.path.relpath(path, ROOT), k + 1, m.group(5)))
    return sorted(out, reverse=True)


def main():
    files = list(sources())
    found = cycles(files)
    print(f"import cycles between files: {len(found)}")
    for component in found:
        print("  " + " ⇄ ".join(component))
    big = [
        (open(p).read().count("\n"), os.path.relpath(p, ROOT))
        for b, p in files
        if b == "src"
    ]
    big = sorted((n, p) for n, p in big if n > 1000)
    print(f"files of src/ over 1,000 lines: {len(big)}")
    for n, p in big:
        print(f"  {n:5} {p}")
    longest = long_functions(files)
    print(f"functions over 100 lines: {len(longest)}")
    for n, p, line, name in longest:
        print(f"  {n:4} {p}:{line} {name}")
    for what, pattern in [
        ("Variant::Lowres", r"Variant::Lowres\b"),
        ("#[doc(hidden)]", r"#\[doc\(hidden\)\]"),
        ("allow(clippy::too_many_arguments)", r"too_many_arguments"),
    ]:
        hits = [
            f"{os.path.relpath(p, ROOT)}:{i + 1}"
            for _, p in files
            for i, line in enumerate(open(p).read().split("\n"))
            if re.search(pattern, line) and not line.strip().startswith("//")
        ]
        print(f"{what}: {len(hits)}" + "".join(f"\n  {h}" for h in hits))


if __name__ == "__main__":
    main()
