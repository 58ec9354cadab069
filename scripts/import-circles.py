#!/usr/bin/env python3
"""Import circles between the source files of each workspace crate.

A file A imports a file B when A's non-test code names a path into B: `use crate::b::X`,
`crate::b::f(...)`, `super::b`, `self::b` (groups `use crate::{a, b::{X}}` expanded), or a
name that another module re-exports from B (`pub use`, `pub(crate) use`, renamed with `as`,
or by a glob `pub use b::*` when B defines the name). A module's reach into its own
descendants is not counted: a parent declares its children (`mod b;`), re-exports them and
dispatches to them, which is the module tree itself.

Not seen: paths inside macro bodies and macros imported with `#[macro_use]`; `super::`
inside a non-test inline `mod` is read as if written at the file's top level. Items under
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


def squeeze(tree):
    """A `use` tree without whitespace, `x as y` kept as `x@y`."""
    return re.sub(r"\s+", "", re.sub(r"\s+as\s+", "@", tree))


def use_trees(code, public_only=False):
    """Every path of every `use` declaration (only `pub`/`pub(..)` ones with `public_only`),
    groups expanded, as (segments, name) pairs: `name` is what the path is known as here
    (its last segment or its alias; `*` for a glob)."""
    out = []
    pattern = r"\bpub(\([^)]*\))?\s+use\s+" if public_only else r"\buse\s+"
    for m in re.finditer(pattern, code):
        end = code.find(";", m.end())
        if end < 0:
            continue
        for segs in expand(squeeze(code[m.end():end])):
            last, _, alias = segs[-1].partition("@")
            out.append((segs[:-1] + [last], alias or last))
    return out


def expand(tree):
    """`a::{b,c::{d}}` -> [[a,b], [a,c,d]] (`self` in a group names the prefix itself)."""
    i = tree.find("{")
    if i < 0:
        return [tree.split("::")] if tree else []
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


DEFINES = r"\b(fn|struct|enum|union|trait|type|const|static|mod)\s+{}\b"


class Crate:
    """A crate's file modules, their non-test code and what each re-exports."""

    def __init__(self, modules, code):
        self.modules, self.code = modules, code
        # (module, name) -> the path it re-exports under that name; module -> glob paths
        self.reexports, self.globs = {}, {}
        for m, c in code.items():
            for segs, name in use_trees(c, public_only=True):
                if name == "*":
                    self.globs.setdefault(m, []).append(segs[:-1])
                else:
                    self.reexports[(m, name)] = segs

    def defines(self, module, name):
        return re.search(DEFINES.format(re.escape(name)), self.code[module]) is not None

    def resolve(self, segments, here, depth=0):
        """The file module (tuple) where a path written in module `here` lands, following
        re-exports (any visibility, aliases, globs); None outside the crate."""
        if not segments or depth > 16:
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
        elif (here + (head,)) in self.modules:
            base, rest = here, segments
        else:
            return None
        if base not in self.modules:
            return None
        best, k = base, 0
        while k < len(rest) and best + (rest[k],) in self.modules:
            best, k = best + (rest[k],), k + 1
        if k < len(rest):
            name = rest[k]
            if (best, name) in self.reexports:
                t = self.resolve(self.reexports[(best, name)], best, depth + 1)
                if t is not None:
                    return t
            elif not self.defines(best, name):
                for g in self.globs.get(best, []):
                    t = self.resolve(g, best, depth + 1)
                    if t is not None and self.defines(t, name):
                        return t
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
    crate = Crate(modules, code)
    edges = {m: {} for m in modules}
    for m, c in code.items():
        for segs in [u[0] for u in use_trees(c)] + inline_paths(c):
            t = crate.resolve(segs, m)
            # A module's reach into its own descendants is not counted: a parent declares its
            # children (`mod`), re-exports them (`pub use child::X`) and dispatches to them;
            # Rust's module tree is that structure. A child's reach up, or any reach across
            # (through re-exports too), is an import.
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
        # through a `pub(crate) use` of an intermediate module, renamed: f -> m/leg (via m),
        # leg -> g, g -> f; one circle
        "reexported": {
            "lib.rs": "mod f;\nmod g;\nmod m;\n",
            "m/mod.rs": "mod leg;\npub(crate) use leg::{Mark as Symbol, draw};\n",
            "m/leg.rs": "pub struct Mark;\npub fn draw() { crate::g::dot() }\n",
            "g.rs": "use crate::f::Scale;\npub fn dot() {}\n",
            "f.rs": "use crate::m::Symbol;\npub struct Scale;\n",
        },
        # a glob re-export: f -> leg through `pub use leg::*`, leg -> f; one circle
        "glob": {
            "lib.rs": "mod f;\nmod m;\n",
            "m/mod.rs": "mod leg;\npub use leg::*;\n",
            "m/leg.rs": "pub fn draw() { crate::f::g() }\n",
            "f.rs": "pub fn g() { crate::m::draw() }\n",
        },
    }
    want = {"circle": 1, "clean": 0, "nested": 1, "reexported": 1, "glob": 1}
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
