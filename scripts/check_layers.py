#!/usr/bin/env python3
"""Checks the module layering of the library (src/, not src/bin).

Every reference to a module of the crate in code (`use crate::x::…`, `crate::x::f(…)`,
`use crate::{x, y::z}`, and `super::…` paths that climb to the crate root) is taken as an
edge from the referring file's *unit* to the module named. A unit is a top-level module: a
top-level file (`src/weld.rs` is `weld`) or a top-level folder with everything in it
(`src/io/**` is `io`). A name the root re-exports (`crate::ScalarGrid`) counts as its
module (`grid`). Comments and doc links do not count; `src/lib.rs` (the root, which
declares and re-exports every module) is no unit.

It fails (exit status 1) when
  1. two or more units import each other in a circle (files of one folder importing each
     other is allowed: that is inside one unit);
  2. `io`, the mesher (`extract`, `decompose`, `clip`, `warp`, `weld`, `keys`) or the
     analysis (`facts`, `report`, `topology`, `check`, `inspect`, `surface`) import
     `improve`;
  3. `io` imports an algorithm module (`extract`, `decompose`, `clip`, `warp`, `weld`,
     `improve`, `critical`, `check`, `sdf`, `surface`, `topology`).
Test code (`#[cfg(test)]` modules, inline or in their own file) is left out of the rules
and of the cycles, but its edges are listed with `-v`.

Usage: scripts/check_layers.py [-v]   (from anywhere; prints the edges with -v)
"""

import re
import sys
from collections import defaultdict
from pathlib import Path

SRC = Path(__file__).resolve().parent.parent / "src"

MESHER = {"extract", "decompose", "clip", "warp", "weld", "keys"}
ANALYSIS = {"facts", "report", "topology", "check", "inspect", "surface"}
ALGORITHMS = {"extract", "decompose", "clip", "warp", "weld", "improve", "critical",
              "check", "sdf", "surface", "topology"}


def blank(text):
    """`text` with comments, strings and char literals replaced by spaces (newlines kept)."""
    out, i, n = [], 0, len(text)

    def spaces(s):
        return re.sub(r"[^\n]", " ", s)

    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(spaces(text[i:j]))
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
            out.append(spaces(text[i:j]))
            i = j
        elif (m := re.compile(r'b?r(#*)"').match(text, i)) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            end = '"' + m.group(1)
            j = text.find(end, m.end())
            j = n if j < 0 else j + len(end)
            out.append(spaces(text[i:j]))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append(spaces(text[i:j + 1]))
            i = j + 1
        elif c == "'" and (m := re.compile(r"'(\\.[^']*|[^\\'])'").match(text, i)):
            out.append(spaces(m.group(0)))
            i = m.end()
        else:
            out.append(c)
            i += 1
    return "".join(out)


def unit_of(path):
    """The unit of a file under src/ and its module path (`["io", "vtu"]`)."""
    rel = path.relative_to(SRC).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "mod":
        parts.pop()
    return parts[0], parts


def test_files():
    """Files that are `#[cfg(test)] mod x;` of their parent."""
    tests = set()
    for path in SRC.rglob("*.rs"):
        code = blank(path.read_text())
        for m in re.finditer(r"#\[cfg\(test\)\]\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;", code):
            base = path.parent if path.name in ("mod.rs", "lib.rs") else path.with_suffix("")
            for cand in (base / f"{m.group(1)}.rs", base / m.group(1) / "mod.rs"):
                if cand.exists():
                    tests.add(cand)
    # a test file's submodules are test code too
    return {p for p in SRC.rglob("*.rs") if any(t == p or (t.name == "mod.rs" and t.parent in p.parents) for t in tests)}


def inline_mods(code):
    """(start, end, is_test) of every inline `mod x { … }` in blanked `code`."""
    spans = []
    for m in re.finditer(r"(#\[cfg\(test\)\]\s*)?(?:pub(?:\([^)]*\))?\s+)?mod\s+\w+\s*\{", code):
        depth, j = 1, m.end()
        while j < len(code) and depth:
            depth += {"{": 1, "}": -1}.get(code[j], 0)
            j += 1
        spans.append((m.start(), j, bool(m.group(1))))
    return spans


def group_items(code, start):
    """The first path segment of every item of the `{…}` group opening at `start`."""
    depth, j, items, cur = 0, start, [], ""
    while j < len(code):
        c = code[j]
        if c == "{":
            depth += 1
            if depth > 1:
                cur += c
        elif c == "}":
            depth -= 1
            if depth == 0:
                break
            cur += c
        elif c == "," and depth == 1:
            items.append(cur)
            cur = ""
        else:
            cur += c
        j += 1
    items.append(cur)
    return [re.match(r"\s*(\w+)", it).group(1) for it in items if re.match(r"\s*\w", it)]


def references(path):
    """(unit named, line, is_test) for every crate-level module reference in `path`."""
    code = blank(path.read_text())
    _, mod_path = unit_of(path)
    spans = inline_mods(code)
    refs = []
    for m in re.finditer(r"(?<![\w$])((?:crate|super)(?:\s*::\s*super)*)\s*::\s*(\{|\w+)", code):
        head, nxt = m.group(1), m.group(2)
        inner = [s for s in spans if s[0] <= m.start() < s[1]]
        if head.startswith("crate"):
            target = []
        else:
            ups = head.count("super")
            here = mod_path + ["<inline>"] * len(inner)
            if ups > len(here):
                continue
            target = here[: len(here) - ups]
        if len(target) >= 1:
            continue  # stays inside the unit (or an inline module of it)
        names = group_items(code, m.start(2)) if nxt == "{" else [nxt]
        line = code.count("\n", 0, m.start()) + 1
        is_test = any(s[2] for s in inner)
        for name in names:
            if name in ("self", "super", "crate"):
                continue
            refs.append((name, line, is_test))
    return refs


def root_reexports():
    """The module of every name `src/lib.rs` re-exports (`Method` is `extract`'s)."""
    code = blank((SRC / "lib.rs").read_text())
    names = {}
    for m in re.finditer(r"pub\s+use\s+(\w+)\s*::([^;]*);", code):
        for name in re.findall(r"\w+", m.group(2)):
            names[name] = m.group(1)
    return names


def cycles(edges):
    """The strongly connected components with more than one unit (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def main():
    verbose = "-v" in sys.argv[1:]
    sys.setrecursionlimit(10000)
    tests = test_files()
    reexports = root_reexports()
    units = {unit_of(p)[0] for p in SRC.rglob("*.rs") if p.parent != SRC / "bin" and SRC / "bin" not in p.parents and p.name != "lib.rs"}
    edges = defaultdict(set)
    where = defaultdict(list)
    test_edges = defaultdict(list)
    for path in sorted(SRC.rglob("*.rs")):
        if path.name == "lib.rs" or SRC / "bin" in path.parents:
            continue
        unit, _ = unit_of(path)
        rel = path.relative_to(SRC.parent)
        for name, line, is_test in references(path):
            name = name if name in units else reexports.get(name, name)
            if name == unit or name not in units:
                continue  # own unit, or a re-export of the root (`crate::TetMesh`)
            if is_test or path in tests:
                test_edges[(unit, name)].append(f"{rel}:{line}")
                continue
            edges[unit].add(name)
            where[(unit, name)].append(f"{rel}:{line}")
    problems = []
    for comp in cycles(edges):
        inner = [f"{a} -> {b} ({where[(a, b)][0]})" for a in comp for b in sorted(edges[a]) if b in comp]
        problems.append("cycle between " + ", ".join(comp) + ":\n    " + "\n    ".join(inner))
    for unit in sorted(edges):
        if "improve" in edges[unit] and (unit == "io" or unit in MESHER or unit in ANALYSIS):
            problems.append(f"{unit} imports improve: {', '.join(where[(unit, 'improve')])}")
        if unit == "io":
            for b in sorted(edges[unit] & ALGORITHMS):
                problems.append(f"io imports the algorithm module {b}: {', '.join(where[('io', b)])}")
    if verbose:
        for (a, b), locs in sorted(where.items()):
            print(f"{a} -> {b}: {', '.join(locs[:3])}{' …' if len(locs) > 3 else ''}")
        for (a, b), locs in sorted(test_edges.items()):
            print(f"(test) {a} -> {b}: {', '.join(locs[:3])}{' …' if len(locs) > 3 else ''}")
    for p in problems:
        print("check_layers:", p)
    if problems:
        sys.exit(1)
    print(f"check_layers: {len(units)} units, {sum(map(len, edges.values()))} edges, no cycle, layers hold")


if __name__ == "__main__":
    main()
