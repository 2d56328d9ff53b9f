#!/usr/bin/env python3
"""Checks the source layout rules of docs/ARCHITECTURE.md:

  * no function longer than MAX_FUNCTION_LINES and no source file longer than MAX_FILE_LINES
    in libs/, apps/ and bench/;
  * libs/core includes no third-party library but Eigen (no MRPT, OctoMap, OpenCV, PCL, OpenNI);
  * libs/sim includes only Eigen, the C++ standard library, upd/core and upd/sim.

Usage: check-layout.py [--max-function N] [--max-file N] [ROOT]   (ROOT: the repository, by
default the parent of this script's folder). Prints one line per violation and exits 1 when
there is any, 0 otherwise. Run by ctest as the `layout` test.

Function lengths are measured on the source with comments, strings and preprocessor lines
removed, by matching braces: a brace block whose header ends in `)` (or `const`, `override`,
`noexcept`) outside any other function is a function; lambdas and blocks inside a function count
towards it."""
import os
import re
import sys

MAX_FUNCTION_LINES = 80
MAX_FILE_LINES = 600
SIZE_CHECKED_DIRS = ("libs", "apps", "bench")
SOURCE_SUFFIXES = (".cpp", ".cc", ".h", ".hpp")

# The C++ standard library's headers (and the C headers it carries as <cname>).
STD_HEADERS = set("""
algorithm any array atomic bit bitset cassert cctype cerrno cfenv cfloat charconv chrono cinttypes
climits clocale cmath codecvt compare complex concepts condition_variable cstdarg cstddef cstdint
cstdio cstdlib cstring ctime cuchar cwchar cwctype deque exception execution filesystem
forward_list fstream functional future initializer_list iomanip ios iosfwd iostream istream
iterator limits list locale map memory memory_resource mutex new numbers numeric optional ostream
queue random ranges ratio regex scoped_allocator set shared_mutex source_location span sstream
stack stdexcept streambuf string string_view system_error thread tuple type_traits typeindex
typeinfo unordered_map unordered_set utility valarray variant vector version
""".split())

# What libs/core may not include: every third-party library but Eigen.
FORBIDDEN_IN_CORE = re.compile(r"^(mrpt/|octomap/|opencv|pcl/|pcl_|OpenNI|openni|ni2?/)",
                               re.IGNORECASE)

INCLUDE_RE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]', re.MULTILINE)


def strip(src):
    """The source with comments, strings and preprocessor lines blanked, line breaks kept."""
    s = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), src, flags=re.S)
    s = re.sub(r"//[^\n]*", "", s)
    s = re.sub(r'R"\((.*?)\)"', lambda m: '""' + "\n" * m.group(0).count("\n"), s, flags=re.S)
    s = re.sub(r'"(\\.|[^"\\\n])*"', '""', s)
    s = re.sub(r"'(\\.|[^'\\\n])*'", "''", s)
    s = re.sub(r"^\s*#.*$", "", s, flags=re.M)
    return s


def long_functions(src, max_lines):
    """(lines, first line, header) of every function longer than max_lines."""
    s = strip(src)
    out = []
    stack = []  # (kind, start line, header)
    line = 1
    last = 0
    for i, ch in enumerate(s):
        if ch == "\n":
            line += 1
        elif ch == "{":
            header = " ".join(s[last:i].split())
            if any(kind == "fn" for kind, _, _ in stack):
                kind = "inner"
            elif re.search(r"\b(namespace|class|struct|union|enum)\b", header) and \
                    not header.endswith(")"):
                kind = "scope"
            elif ")" in header or header.endswith(("const", "override", "noexcept")):
                kind = "fn"
            else:
                kind = "other"
            stack.append((kind, line, header))
            last = i + 1
        elif ch == "}":
            if stack:
                kind, start, header = stack.pop()
                n = line - start + 1
                if kind == "fn" and n > max_lines:
                    out.append((n, start, header))
            last = i + 1
        elif ch == ";":
            last = i + 1
    return out


def function_name(header):
    """The name of the function a block header declares, e.g. `Terrain::raycast()`."""
    paren = header.find("(")
    words = header[:paren].split() if paren > 0 else []
    return (words[-1] + "()") if words else "function: " + header


def source_files(root, folder):
    base = os.path.join(root, folder)
    for dirpath, dirnames, filenames in os.walk(base):
        dirnames[:] = sorted(d for d in dirnames if d != ".git" and not d.startswith("build"))
        for f in sorted(filenames):
            if f.endswith(SOURCE_SUFFIXES):
                yield os.path.join(dirpath, f)


def includes(path):
    """(line, delimiter, included path) of every #include of the file."""
    with open(path, errors="replace") as f:
        src = f.read()
    return [(src.count("\n", 0, m.start()) + 1, m.group(1), m.group(2).strip())
            for m in INCLUDE_RE.finditer(src)]


def sim_include_allowed(path, delim, inc):
    if inc.startswith(("Eigen/", "upd/core/", "upd/sim/")):
        return True
    if delim == "<" and inc in STD_HEADERS:
        return True
    # A private header of libs/sim itself, next to the including file.
    return delim == '"' and os.path.exists(os.path.join(os.path.dirname(path), inc))


def check(root, max_fn, max_file):
    problems = []
    rel = lambda p: os.path.relpath(p, root)
    for folder in SIZE_CHECKED_DIRS:
        for path in source_files(root, folder):
            with open(path, errors="replace") as f:
                src = f.read()
            n = src.count("\n") + (0 if src.endswith("\n") or not src else 1)
            if n > max_file:
                problems.append(f"{rel(path)}: file has {n} lines (> {max_file})")
            for length, start, header in long_functions(src, max_fn):
                problems.append(f"{rel(path)}:{start}: {function_name(header)} has {length} "
                                f"lines (> {max_fn})")
    for path in source_files(root, "libs/core"):
        for line, _, inc in includes(path):
            if FORBIDDEN_IN_CORE.match(inc):
                problems.append(f"{rel(path)}:{line}: libs/core includes {inc} (Eigen only)")
    for path in source_files(root, "libs/sim"):
        for line, delim, inc in includes(path):
            if not sim_include_allowed(path, delim, inc):
                problems.append(f"{rel(path)}:{line}: libs/sim includes {inc} "
                                "(Eigen, std, upd/core, upd/sim only)")
    return problems


def main(argv):
    max_fn, max_file = MAX_FUNCTION_LINES, MAX_FILE_LINES
    args = list(argv)
    root = None
    while args:
        a = args.pop(0)
        if a == "--max-function" and args:
            max_fn = int(args.pop(0))
        elif a == "--max-file" and args:
            max_file = int(args.pop(0))
        elif a in ("-h", "--help"):
            print(__doc__)
            return 0
        elif root is None and not a.startswith("-"):
            root = a
        else:
            print(f"check-layout.py: unexpected argument {a} (see --help)", file=sys.stderr)
            return 2
    root = os.path.abspath(root or os.path.join(os.path.dirname(__file__), ".."))
    if not os.path.isdir(os.path.join(root, "libs")):
        print(f"check-layout.py: {root} has no libs/ folder", file=sys.stderr)
        return 2
    problems = check(root, max_fn, max_file)
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} layout problem(s) (docs/ARCHITECTURE.md, 'Layout rules')")
        return 1
    print("layout: every rule holds")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
