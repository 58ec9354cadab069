#!/usr/bin/env python3
"""Non-test code size of the workspace's Rust sources.

Counts code lines as the usual line counters do: a line counts when it holds
anything but whitespace and comments (line, block and doc comments alike).
Items under `#[cfg(test)]` (inline modules, or `mod x;` files they declare)
and the crates' `tests/`, `benches/`, `examples/` folders are left out.

Prints per crate and per file code lines, and every function whose body spans
more than the limit (raw lines from `fn` to its closing brace).

Usage (from the repository root):
  python3 scripts/code-size.py [-v] [--fn-limit N] [--file-limit N] [--max CRATE=N]... [CRATE...]
-v lists every file; otherwise only files over the file limit (default 1000 code lines)
and functions over the function limit (default 150 lines) are listed. `--max CRATE=N`
caps a crate's code lines. Exits 1 when a limit is exceeded (CI runs it: .ci/run).
"""
import os
import re
import sys


def mask(src):
    """Returns (masked, code_line_flags): comments and literal contents blanked."""
    out = []
    code = set()
    i, n, line = 0, len(src), 0
    while i < n:
        c = src[i]
        if c == "\n":
            out.append(c)
            line += 1
            i += 1
        elif src.startswith("//", i):
            j = src.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif src.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if src.startswith("/*", j):
                    depth += 1
                    j += 2
                elif src.startswith("*/", j):
                    depth -= 1
                    j += 2
                else:
                    j += 1
            seg = src[i:j]
            out.append(re.sub(r"[^\n]", " ", seg))
            line += seg.count("\n")
            i = j
        else:
            m = re.compile(r'b?r(#*)"').match(src, i)
            if m and (i == 0 or not (src[i - 1].isalnum() or src[i - 1] == "_")):
                end = '"' + m.group(1)
                j = src.find(end, m.end())
                j = n if j < 0 else j + len(end)
                seg = src[i:j]
                for k in range(seg.count("\n") + 1):
                    code.add(line + k)
                out.append('"' + re.sub(r"[^\n]", " ", seg[1:-1]) + '"' if len(seg) > 1 else seg)
                line += seg.count("\n")
                i = j
                continue
            if c == '"' or (c == "b" and src.startswith('b"', i) and not (i > 0 and (src[i-1].isalnum() or src[i-1] == "_"))):
                j = i + (2 if c == "b" else 1)
                while j < n and src[j] != '"':
                    j += 2 if src[j] == "\\" else 1
                j += 1
                seg = src[i:j]
                for k in range(seg.count("\n") + 1):
                    code.add(line + k)
                out.append('"' + re.sub(r"[^\n]", " ", seg[1:-1]) + '"')
                line += seg.count("\n")
                i = j
                continue
            if c == "'":
                m = re.compile(r"'(\\.[^']*|[^\\'])'").match(src, i)
                if m:
                    out.append("' '" + " " * (m.end() - i - 3))
                    code.add(line)
                    i = m.end()
                    continue
            if not c.isspace():
                code.add(line)
            out.append(c)
            i += 1
    return "".join(out), code


def match_brace(masked, open_idx):
    depth = 0
    for j in range(open_idx, len(masked)):
        ch = masked[j]
        if ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
            if depth == 0:
                return j
    return len(masked) - 1


CFG_TEST = re.compile(r"#\[cfg\(\s*(test|all\(test[^\]]*)\s*\)\]")
MOD_DECL = re.compile(r"\s*(pub(\([^)]*\))?\s+)?mod\s+(\w+)\s*([;{])")


def test_spans(masked):
    """Line spans (start, end inclusive) of #[cfg(test)] items; file mods declared."""
    spans, files = [], []
    for m in CFG_TEST.finditer(masked):
        j = m.end()
        # skip further attributes
        while True:
            k = re.compile(r"\s*#\[[^\]]*\]").match(masked, j)
            if not k:
                break
            j = k.end()
        d = MOD_DECL.match(masked, j)
        start = masked.count("\n", 0, m.start())
        if d and d.group(4) == ";":
            files.append(d.group(3))
            end_idx = d.end()
        else:
            semi = masked.find(";", j)
            brace = masked.find("{", j)
            if brace >= 0 and (semi < 0 or brace < semi):
                end_idx = match_brace(masked, brace)
            else:
                end_idx = semi
        spans.append((start, masked.count("\n", 0, end_idx)))
    return spans, files


FN = re.compile(r"(?m)^[ \t]*(pub(\([^)]*\))?\s+)?((const|async|unsafe|extern\s+\"\w+\")\s+)*fn\s+(\w+)")


def functions(masked):
    for m in FN.finditer(masked):
        # find the body's opening brace, or a ';' (declaration)
        j = m.end()
        depth = 0
        while j < len(masked):
            ch = masked[j]
            if ch in "(<[":
                depth += 1
            elif ch in ")>]":
                depth -= 1 if not (ch == ">" and masked[j - 1] == "-") else 0
            elif ch == ";" and depth <= 0:
                j = -1
                break
            elif ch == "{" and depth <= 0:
                break
            j += 1
        if j < 0 or j >= len(masked):
            continue
        end = match_brace(masked, j)
        yield m.group(5), masked.count("\n", 0, m.start()), masked.count("\n", 0, end)


def exclude_test_files(path, files, excluded_files):
    """Adds the paths of `path`'s `#[cfg(test)] mod f;` files (`files`) to `excluded_files`."""
    here = os.path.dirname(path)
    stem = os.path.splitext(os.path.basename(path))[0]
    mod_dir = here if stem in ("lib", "main", "mod") else os.path.join(here, stem)
    for f in files:
        excluded_files.add(os.path.join(mod_dir, f + ".rs"))
        excluded_files.add(os.path.join(mod_dir, f, "mod.rs"))


def analyse(path, excluded_files):
    src = open(path, encoding="utf-8").read()
    masked, code = mask(src)
    spans, files = test_spans(masked)
    exclude_test_files(path, files, excluded_files)
    in_test = set()
    for a, b in spans:
        in_test.update(range(a, b + 1))
    lines = sum(1 for l in code if l not in in_test)
    fns = []
    for name, a, b in functions(masked):
        if a in in_test:
            continue
        body_code = sum(1 for l in code if a <= l <= b)
        fns.append((name, a + 1, b - a + 1, body_code))
    return lines, fns


def main():
    args = sys.argv[1:]
    fn_limit, file_limit = 150, 1000
    crates, caps = [], {}
    while args:
        a = args.pop(0)
        if a == "--fn-limit":
            fn_limit = int(args.pop(0))
        elif a == "--file-limit":
            file_limit = int(args.pop(0))
        elif a == "--max":
            name, n = args.pop(0).split("=")
            caps[name] = int(n)
        elif a != "-v":
            crates.append(a)
    over = 0
    root = os.path.join(os.getcwd(), "crates")
    crates = crates or sorted(os.listdir(root))
    for crate in crates:
        src_dir = os.path.join(root, crate, "src")
        paths = []
        for d, _, fs in os.walk(src_dir):
            paths += [os.path.join(d, f) for f in fs if f.endswith(".rs")]
        excluded = set()
        results = {}
        # parents first so their `#[cfg(test)] mod x;` exclusions are known
        for p in sorted(paths, key=lambda p: (p.count(os.sep), p)):
            if p in excluded:
                continue
            results[p] = analyse(p, excluded)
        results = {p: r for p, r in results.items() if p not in excluded}
        total = sum(r[0] for r in results.values())
        cap = caps.get(crate)
        flag = f"  OVER {cap}" if cap is not None and total > cap else ""
        over += bool(flag)
        print(f"{crate}: {total} code lines{flag}")
        for p, (lines, fns) in sorted(results.items()):
            rel = os.path.relpath(p, root)
            flag = "  OVER FILE LIMIT" if lines > file_limit else ""
            over += bool(flag)
            if "-v" in sys.argv or flag:
                print(f"  {lines:6} {rel}{flag}")
            for name, line, span, body in fns:
                if span > fn_limit:
                    over += 1
                    print(f"  fn {rel}:{line} {name}: {span} lines ({body} code)")
    sys.exit(1 if over else 0)


if __name__ == "__main__":
    main()
