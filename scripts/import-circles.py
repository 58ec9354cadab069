#!/usr/bin/env python3
"""Import circles between the source files of each workspace crate.

A file A imports a file B when A's non-test code names a path into B: `use crate::b::X`,
`crate::b::f(...)`, `super::b`, `self::b` (groups `use crate::{a, b::{X}}` expanded), or
a name that the crate root re-exports from B (`pub use b::X;` in lib.rs, then
`use crate::X` elsewhere). A module's reach into its own submodules (`mod b;`,
`pub use b::X;`, `use b::*`) declares or re-exports them and is not an import. Items under
`#[cfg(test)]` are left out, as are the crates' `tests/`, `benches/` and `examples/`.

Prints every circle (a strongly connected set of two or more files) with the names that tie
it, and exits 1 when there is one; `--quiet` prints only circles.

Usage (from the repository root):
  python3 scripts/import-circles.py [--quiet] [CRATE...]
  python3 scripts/import-circles.py --self-test   # the detector on small fixture crates
"""
import importlib.util
import os
import re
import sys

_spec = importlib.util.spec_from_file_location(
    "code_size", os.path.join(os.path.dirname(os.path.abspath(__file__)), "code-size.py")
)
code_size = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(code_size)

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"


def module_path(src_dir, path):
    """`crate::a::b` of a file as a tuple ('a', 'b'); () for the crate root."""
    rel = os.path.relpath(path, src_dir)[: -len(".rs")].split(os.sep)
    if rel[-1] in ("lib", "main", "mod"):
        rel = rel[:-1]
    return tuple(rel)


def strip_tests(masked):
    """`masked` with every #[cfg(test)] item blanked."""
    spans, _ = code_size.test_spans(masked)
    lines = masked.split("\n")
    for a, b in spans:
        for k in range(a, min(b, len(lines) - 1) + 1):
            lines[k] = ""
    return "\n".join(lines)


def use_trees(code):
    """Every path of every `use` declaration, groups expanded, as lists of segments."""
    out = []
    for m in re.finditer(r"\buse\s+", code):
        end = code.find(";", m.end())
        if end < 0:
            continue
        out += expand(re.sub(r"\s+", "", code[m.end():end]))
    return out


def expand(tree):
    """`a::{b,c::{d}}` -> [[a,b], [a,c,d]] (`self` in a group names the prefix itself)."""
    i = tree.find("{")
    if i < 0:
        return [tree.split(" as ")[0].split("::")] if tree else []
    prefix = [p for p in tree[:i].split("::") if p]
    body = tree[i + 1 : tree.rfind("}")]
    parts, depth, cur = [], 0, ""
    for ch in body:
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
            continue
        depth += ch == "{"
        depth -= ch == "}"
        cur += ch
    parts.append(cur)
    out = []
    for p in parts:
        for sub in expand(p):
            out.append(prefix + [s for s in sub if s != "self"] if sub != ["self"] else prefix)
    return out


def inline_paths(code):
    """`crate::a::b`, `super::a`, `self::a` paths written in expressions and types."""
    return [
        m.group(0).split("::")
        for m in re.finditer(rf"\b(crate|super|self)(::{IDENT})+", code)
    ]


def resolve(segments, here, modules, reexports):
    """The module (tuple) that a path from module `here` lands in, or None."""
    if not segments:
        return None
    head, rest = segments[0], segments[1:]
    if head == "crate":
        base = ()
    elif head == "super":
        base = here[:-1]
        while rest and rest[0] == "super":
            base, rest = base[:-1], rest[1:]
    elif head == "self":
        base = here
    else:
        base = here
        rest = segments
        if (here + (head,)) not in modules:
            return None
    best = base if base in modules else None
    cur = base
    for s in rest:
        cur = cur + (s,)
        if cur in modules:
            best = cur
        else:
            break
    if best == () and rest and rest[0] in reexports:
        return reexports[rest[0]]
    return best


def crate_graph(src_dir):
    paths = []
    for d, _, fs in os.walk(src_dir):
        paths += [os.path.join(d, f) for f in fs if f.endswith(".rs")]
    modules, code = {}, {}
    excluded = set()
    for p in sorted(paths, key=lambda p: (p.count(os.sep), p)):
        if p in excluded:
            continue
        masked, _ = code_size.mask(open(p, encoding="utf-8").read())
        code_size.exclude_test_files(p, code_size.test_spans(masked)[1], excluded)
        m = module_path(src_dir, p)
        modules[m] = os.path.relpath(p)
        code[m] = strip_tests(masked)
    reexports = {}
    root = code.get(())
    if root is not None:
        for m in re.finditer(r"\bpub\s+use\s+", root):
            end = root.find(";", m.end())
            for segs in expand(re.sub(r"\s+", "", root[m.end():end])):
                target = resolve(segs, (), modules, {})
                if target not in (None, ()) and segs:
                    reexports[segs[-1]] = target
    edges = {m: {} for m in modules}
    for m, c in code.items():
        for segs in use_trees(c) + inline_paths(c):
            t = resolve(segs, m, modules, reexports)
            # A module's reach into its own submodules declares or re-exports them (`mod`,
            # `pub use child::X`): structure, not an import. The other way is one.
            if t is None or t[: len(m)] == m:
                continue
            edges[m].setdefault(t, set()).add("::".join(segs))
    return modules, edges


def circles(nodes, edges):
    """Strongly connected sets of two or more nodes (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

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
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in nodes:
        if v not in index:
            visit(v)
    return out


def self_test():
    """Checks the detector on small crates written to a temporary directory."""
    import tempfile

    cases = {
        # a <-> b through a re-export of the root, and b -> a directly: one circle
        "circle": {
            "lib.rs": "mod a;\nmod b;\npub use a::A;\npub use b::{B, helper};\n",
            "a.rs": "use crate::helper;\npub struct A;\n",
            "b.rs": "use crate::A;\npub struct B;\npub fn helper() {}\n",
        },
        # a parent re-exporting and declaring its children, children using the parent and
        # each other one way, a test module reaching back: no circle
        "clean": {
            "lib.rs": "mod a;\nmod b;\npub use b::B;\npub struct Root;\n",
            "a.rs": "use crate::{Root, b::B};\npub struct A(pub B, pub Root);\n",
            "b/mod.rs": "mod c;\npub use c::C;\npub struct B;\n"
            "#[cfg(test)]\nmod tests {\n    use crate::a::A;\n}\n",
            "b/c.rs": "use super::super::Root;\npub struct C(pub Root);\n",
        },
        # a nested module reaching its sibling through `super::` and back: one circle
        "nested": {
            "lib.rs": "mod m;\n",
            "m/mod.rs": "mod x;\nmod y;\n",
            "m/x.rs": "use super::y::Y;\npub struct X;\n",
            "m/y.rs": "pub struct Y;\nfn f() -> super::x::X { super::x::X }\n",
        },
    }
    want = {"circle": 1, "clean": 0, "nested": 1}
    with tempfile.TemporaryDirectory() as tmp:
        for name, files in cases.items():
            src = os.path.join(tmp, name, "src")
            for rel, text in files.items():
                path = os.path.join(src, rel)
                os.makedirs(os.path.dirname(path), exist_ok=True)
                with open(path, "w", encoding="utf-8") as f:
                    f.write(text)
            modules, edges = crate_graph(src)
            got = len(circles(list(modules), edges))
            if got != want[name]:
                print(f"self-test {name}: {got} circles, expected {want[name]}", file=sys.stderr)
                sys.exit(1)
    print("self-test passed")


def main():
    if "--self-test" in sys.argv:
        self_test()
        return
    args = [a for a in sys.argv[1:] if a != "--quiet"]
    quiet = "--quiet" in sys.argv
    root = os.path.join(os.getcwd(), "crates")
    crates = args or sorted(os.listdir(root))
    found = 0
    for crate in crates:
        src_dir = os.path.join(root, crate, "src")
        if not os.path.isdir(src_dir):
            continue
        modules, edges = crate_graph(src_dir)
        comps = circles(list(modules), edges)
        if not quiet:
            print(f"{crate}: {len(modules)} files, {sum(len(e) for e in edges.values())} imports, {len(comps)} circles")
        for comp in comps:
            found += 1
            print(f"circle in {crate}: " + ", ".join(modules[m] for m in comp))
            for a in comp:
                for b in comp:
                    if b in edges[a]:
                        names = ", ".join(sorted(edges[a][b]))
                        print(f"  {modules[a]} -> {modules[b]}: {names}")
    sys.exit(1 if found else 0)


if __name__ == "__main__":
    main()
