#!/usr/bin/env python3
"""Checks that keep the documentation honest (run by ctest, see tests/docs/CMakeLists.txt).

  extract    write every complete C++/Python program of README.md and docs/*.md to a folder, with
             its expected output, and a manifest CMake turns into one executable and one test each
  run        run one extracted program and compare what it prints with the output the doc states
  citations  every "spec §x.y" cited in the sources and docs is a heading of docs/specification.md,
             and every erratum "E<n>" cited is one the specification lists
  umbrella   implicit/implicit.hpp includes every public header
  versions   CMakeLists.txt, CITATION.cff, CHANGELOG.md and `implicit --version` name one version,
             and the changelog dates it as CITATION.cff does (not "unreleased")
  numbers    rerun the command of one `<!-- numbers: ... -->` comment and check that the numbers
             it lists are what the command gives and what the doc's text says (list: lists them)

The conventions for authors are in docs/design.md, "Tested documentation":
  ```cpp                        a complete program: compiled, linked with implicit::implicit, run
  ```cpp fragment               a piece of a program: not compiled
  ```output                     what the program just above prints, compared exactly
  ```output tolerance=1e-3      ... every number within 1e-3 * max(1, |expected|), text exactly
The same holds for ```python blocks (run with the built package, PYTHONPATH=build/python), and a
```robot-log block (docs/formats.md) is run through `implicit mcl --data` and must be scored.
A number the prose states comes with the command that gives it, in a comment the reader does not
see (docs/design.md, "Numbers in the docs"):
  <!-- numbers: implicit mcl --init global --runs 20 --json
  global_success_rate 1.0
  particles_mean 1834
  -->
"""
import argparse
import json
import pathlib
import re
import shlex
import subprocess
import sys

PROGRAM_LANGUAGES = {"cpp": "cpp", "c++": "cpp", "python": "py", "py": "py", "robot-log": "txt"}
FENCE = re.compile(r"^(```+)\s*([^\s`]*)\s*(.*)$")
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def fenced_blocks(path):
    """Yields (line, language, flags, text) for every fenced block of a Markdown file."""
    lines = path.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m or "`" in m.group(3):  # a backtick in the info string: inline code, no fence
            i += 1
            continue
        fence, language, flags = m.group(1), m.group(2).lower(), m.group(3).split()
        start, body = i + 1, []
        i += 1
        while i < len(lines) and not lines[i].startswith(fence):
            body.append(lines[i])
            i += 1
        if i == len(lines):
            sys.exit(f"{path}:{start}: unterminated ``` block")
        i += 1
        yield start, language, flags, "\n".join(body) + "\n"


def parse_tolerance(path, line, flags):
    for flag in flags:
        if flag.startswith("tolerance="):
            try:
                return float(flag.split("=", 1)[1])
            except ValueError:
                sys.exit(f"{path}:{line}: expected tolerance=<number>, got '{flag}'")
    return 0.0


def write_if_changed(path, text):
    # Unchanged snippets keep their time stamp, so the build does not recompile them.
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


def joined_program(name, origin, text):
    """The C++ program `text` as one part of the single program that runs every C++ snippet
    (tests/docs/CMakeLists.txt): its #include lines first, the rest in namespace `name` with
    `int main() {` renamed `int program() {` (and a `return 0;` at its end, which main has
    implicitly), then `int NAME_main()` calling it. None when the snippet does not have that
    shape (includes at the top, main last): it is then built as a program of its own."""
    lines = text.rstrip("\n").split("\n")
    includes = [l for l in lines if l.startswith("#include")]
    body = [l for l in lines if not l.startswith("#include")]
    if any(l.startswith("#") for l in body) or body.count("int main() {") != 1 or body[-1] != "}":
        return None
    start = body.index("int main() {")
    if any(l and not l[0].isspace() for l in body[start + 1:-1]):
        return None  # something after main at file scope
    body[start] = "int program() {"
    body.insert(len(body) - 1, "  return 0;")
    return "\n".join([f"// {origin}: {name}.cpp as a part of the one program of the snippets"] +
                     includes + [f"namespace {name} {{"] + body +
                     [f"}}  // namespace {name}", f"int {name}_main() {{ return {name}::program(); }}",
                      ""])


def extract(args):
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    root = pathlib.Path(args.root)
    manifest = []
    for doc in args.docs:
        path = pathlib.Path(doc)
        origin = path.resolve().relative_to(root.resolve()).as_posix()
        current = None  # the last program, waiting for its ```output block
        ordinal = 0
        for line, language, flags, text in fenced_blocks(path):
            if language in PROGRAM_LANGUAGES:
                current = None
                if "fragment" in flags:
                    continue
                # Numbered within the file, so that editing one doc renames no other's targets.
                ordinal += 1
                name = f"doc_{re.sub(r'[^A-Za-z0-9]+', '_', path.stem).lower()}_{ordinal}"
                source = out / f"{name}.{PROGRAM_LANGUAGES[language]}"
                prefix = "// " if PROGRAM_LANGUAGES[language] == "cpp" else "# "
                write_if_changed(source, f"{prefix}{origin}:{line}\n{text}")
                current = {"name": name, "source": source, "language": PROGRAM_LANGUAGES[language],
                           "origin": f"{origin}:{line}", "expected": "", "tolerance": 0.0,
                           "joined": ""}
                joined = (joined_program(name, f"{origin}:{line}", text)
                          if current["language"] == "cpp" else None)
                if joined is not None:
                    current["joined"] = out / f"{name}_joined.cpp"
                    write_if_changed(current["joined"], joined)
                manifest.append(current)
            elif language == "output":
                if current is None:
                    sys.exit(f"{origin}:{line}: an ```output block must follow a program block")
                expected = out / f"{current['name']}.expected"
                write_if_changed(expected, text)
                current["expected"] = expected
                current["tolerance"] = parse_tolerance(origin, line, flags)
                current = None
    rows = [f"{m['name']}|{m['source']}|{m['language']}|{m['origin']}|{m['expected']}|"
            f"{m['tolerance']:g}|{m['joined']}" for m in manifest]
    write_if_changed(pathlib.Path(args.manifest), "\n".join(rows) + "\n")
    # The one program's main: `doc_programs NAME` runs the snippet NAME.
    joined = [m["name"] for m in manifest if m["joined"]]
    write_if_changed(out / "doc_programs_main.cpp", "\n".join(
        ["// The programs of the docs' C++ snippets in one executable: doc_programs NAME runs one.",
         "#include <cstdio>", "#include <cstring>", ""] +
        [f"int {n}_main();" for n in joined] +
        ["", "int main(int argc, char** argv) {"] +
        [f"  if (argc == 2 && std::strcmp(argv[1], \"{n}\") == 0) return {n}_main();"
         for n in joined] +
        ["  std::fprintf(stderr, \"usage: doc_programs NAME (a snippet of the docs)\\n\");",
         "  return 2;", "}", ""]))


def outputs_agree(got, expected, tolerance):
    """Exact text; with a tolerance, the numbers may differ by tolerance * max(1, |expected|)."""
    if tolerance == 0.0:
        return got == expected
    if NUMBER.sub("#", got) != NUMBER.sub("#", expected):
        return False
    for a, b in zip(NUMBER.findall(got), NUMBER.findall(expected)):
        if abs(float(a) - float(b)) > tolerance * max(1.0, abs(float(b))):
            return False
    return True


def run(args):
    result = subprocess.run(args.command, capture_output=True, text=True, timeout=args.timeout)
    sys.stderr.write(result.stderr)
    if result.returncode != 0:
        print(f"{args.origin}: the program exited with {result.returncode}:\n{result.stdout}")
        return 1
    if args.expected:
        expected = pathlib.Path(args.expected).read_text(encoding="utf-8")
        if not outputs_agree(result.stdout, expected, args.tolerance):
            print(f"{args.origin}: the program prints\n{result.stdout}\n"
                  f"but the doc says (tolerance {args.tolerance:g})\n{expected}")
            return 1
    if args.positive:
        # A JSON report whose listed numbers must be > 0: a run that used no detection or scored
        # no step has not shown that the example works.
        try:
            report = json.loads(result.stdout)
        except json.JSONDecodeError as e:
            print(f"{args.origin}: expected JSON on stdout, got {e}:\n{result.stdout}")
            return 1
        for key in args.positive:
            value = report.get(key)
            if not isinstance(value, (int, float)) or not value > 0:
                print(f"{args.origin}: expected '{key}' > 0 in the JSON report, got {value}")
                return 1
    print(f"{args.origin}: ok")
    return 0


HEADING = re.compile(r"^#{1,6}\s+(\d+(?:\.\d+)*)\.?\s")
ERRATUM = re.compile(r"^\s*[-*]?\s*\*\*(E\d+)\*\*")
# "spec §2.4", "specification §3.5", "docs/specification.md §3.5", then ", §3.6" or "–3.7" lists.
CITATION = re.compile(r"\bspec(?:ification)?(?:\.md)?\s*§\s*(\d+(?:\.\d+)*)((?:\s*(?:,|–|-|and)\s*§?\s*\d+(?:\.\d+)*)*)")
ERRATUM_CITED = re.compile(r"(?<![\w.])E(\d+)(?:\s*[–-]\s*E?(\d+))?\b")
NOT_AN_ERRATUM = re.compile(r"noqa[:\s]+[A-Z0-9, ]*$")
# Subjects with a section of their own: a citation on a line that names the subject (or right
# after a line that does, for comments that wrap) must cite that section. A heading that exists is
# not enough: renumbering once left global localization citing §3.10, the SLAM reference table.
TOPIC_SECTIONS = {"3.11": re.compile(r"global locali[sz]ation|kidnap|recovery|KLD", re.I)}


def spec_contents(spec):
    sections, errata = set(), set()
    for line in spec.read_text(encoding="utf-8").splitlines():
        if m := HEADING.match(line):
            sections.add(m.group(1))
        if m := ERRATUM.match(line):
            errata.add(m.group(1))
    return sections, errata


def citations(args):
    root = pathlib.Path(args.root)
    sections, errata = spec_contents(root / "docs" / "specification.md")
    files = [root / "README.md"]
    for folder in ("include", "src", "apps", "tests", "python", "docs", "examples", "bench",
                   "data/report"):  # data/report: the report's text, which cites the spec too
        files += [p for p in sorted((root / folder).rglob("*"))
                  if p.suffix in (".hpp", ".cpp", ".py", ".md", ".txt", ".cmake", ".in", ".json")]
    problems, count = [], 0
    for path in files:
        previous = ""
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            where = f"{path.relative_to(root)}:{number}"
            for m in CITATION.finditer(line):
                cited = [m.group(1)] + re.findall(r"\d+(?:\.\d+)*", m.group(2))
                for section in cited:
                    count += 1
                    if section not in sections:
                        problems.append(f"{where}: cites spec §{section}, not a heading of "
                                        f"docs/specification.md")
                for section, subject in TOPIC_SECTIONS.items():
                    named = subject.search(previous + " " + line)
                    if named and section not in cited:
                        problems.append(f"{where}: cites spec §{', §'.join(cited)} next to "
                                        f"'{named.group(0)}', whose section is §{section}")
            previous = line
            for m in ERRATUM_CITED.finditer(line):
                if NOT_AN_ERRATUM.search(line[:m.start()]):
                    continue
                first = int(m.group(1))
                last = int(m.group(2)) if m.group(2) else first
                for n in {first, last}:
                    count += 1
                    if f"E{n}" not in errata:
                        problems.append(f"{where}: cites erratum E{n}, which docs/specification.md "
                                        f"does not list")
    for p in problems:
        print(p)
    print(f"{count} citations checked against {len(sections)} sections and {len(errata)} errata; "
          f"{len(problems)} unresolved")
    return 1 if problems or not sections or not errata else 0


def umbrella(args):
    include = pathlib.Path(args.root) / "include"
    top = include / "implicit" / "implicit.hpp"
    included = set(re.findall(r'#include\s+"([^"]+)"', top.read_text(encoding="utf-8")))
    headers = {p.relative_to(include).as_posix() for p in include.rglob("*.hpp")
               if p != top and "detail" not in p.parts}
    missing = sorted(headers - included)
    for h in missing:
        print(f"include/implicit/implicit.hpp: does not include \"{h}\"")
    print(f"{len(headers)} public headers, {len(missing)} missing from implicit/implicit.hpp")
    return 1 if missing else 0


def versions(args):
    root = pathlib.Path(args.root)
    found = {}
    m = re.search(r"project\(implicit\s+VERSION\s+([0-9.]+)", (root / "CMakeLists.txt").read_text())
    found["CMakeLists.txt project(VERSION)"] = m.group(1) if m else None
    m = re.search(r"^version:\s*\"?([0-9.]+)", (root / "CITATION.cff").read_text(), re.M)
    found["CITATION.cff version"] = m.group(1) if m else None
    # The newest section of the changelog is the first heading that names a version.
    changelog = (root / "CHANGELOG.md").read_text()
    m = re.search(r"^## .*?(\d+\.\d+\.\d+).*$", changelog, re.M)
    found["CHANGELOG.md newest section"] = m.group(1) if m else None
    # A released version (CITATION.cff's date-released) is not also "unreleased" in the
    # changelog, and both give it the same date; ongoing work goes under "## Unreleased".
    released = re.search(r"^date-released:\s*\"?([0-9-]+)", (root / "CITATION.cff").read_text(),
                         re.M)
    consistent = True
    if m and released:
        heading = m.group(0)
        if "unreleased" in heading.lower() or released.group(1) not in heading:
            print(f"CHANGELOG.md: the section of {m.group(1)} is '{heading}', expected a released "
                  f"version dated {released.group(1)} as in CITATION.cff (ongoing work goes "
                  f"under '## Unreleased')")
            consistent = False
    if args.cli:
        out = subprocess.run([args.cli, "--version"], capture_output=True, text=True).stdout
        m = re.match(r"implicit (\d+\.\d+\.\d+) ", out)
        found["implicit --version"] = m.group(1) if m else None
    for where, version in found.items():
        print(f"{where}: {version}")
    return 0 if consistent and None not in found.values() and len(set(found.values())) == 1 else 1


# <!-- numbers: COMMAND  or  <!-- numbers slow: COMMAND (run by `make docs-check`, not `make test`)
NUMBERS_OPEN = re.compile(r"^<!--\s*numbers(\s+slow)?:\s*(.+?)\s*$")
CLAIM = re.compile(r"^\s*([A-Za-z_][\w.\[\]]*)\s+(\S+)\s*$")


def stated_text(lines, after, command):
    """The text a comment ending on line index `after` speaks for: the next paragraph or table
    (further numbers comments skipped). In a table whose row quotes the command (without --json),
    only that row, less the command."""
    i = after + 1
    while i < len(lines):
        if NUMBERS_OPEN.match(lines[i]):
            while i < len(lines) and lines[i].strip() != "-->":
                i += 1
            i += 1
        elif not lines[i].strip():
            i += 1
        else:
            break
    block = []
    while i < len(lines) and lines[i].strip() and not NUMBERS_OPEN.match(lines[i]):
        block.append(lines[i])
        i += 1
    quoted = re.sub(r"\s+--json\b", "", command).strip()
    # The row's own command is not a statement of its numbers (`-N 100` is not a result of 100).
    rows = [b.replace(quoted, "") for b in block if b.lstrip().startswith("|") and quoted in b]
    return "\n".join(rows or block)


def numbers_comments(path):
    """Yields (line, slow, command, [(key, text)], problems) for every numbers comment."""
    lines = path.read_text(encoding="utf-8").splitlines()
    i, fence = 0, None
    while i < len(lines):
        f = FENCE.match(lines[i])
        if f and (fence is None or lines[i].startswith(fence)):
            fence = f.group(1) if fence is None else None  # an example in a code block: not one
        m = NUMBERS_OPEN.match(lines[i]) if fence is None else None
        if not m:
            i += 1
            continue
        start, claims, problems = i + 1, [], []
        i += 1
        while i < len(lines) and lines[i].strip() != "-->":
            c = CLAIM.match(lines[i])
            if c and re.fullmatch(r"-?\d+(\.\d+)?", c.group(2)):
                claims.append((c.group(1), c.group(2)))
            else:
                problems.append(f"{path}:{i + 1}: expected 'KEY NUMBER' (a JSON key and the number "
                                f"as the text writes it, e.g. 0.303), got '{lines[i].strip()}'")
            i += 1
        if i == len(lines):
            problems.append(f"{path}:{start}: the numbers comment has no closing '-->' line")
        text = stated_text(lines, i, m.group(2))
        for key, written in claims:
            if not re.search(r"(?<![\d.])" + re.escape(written) + r"(?![\d])", text):
                problems.append(f"{path}:{start}: '{key} {written}': the paragraph or table row "
                                f"below the comment does not state {written}")
        if not claims:
            problems.append(f"{path}:{start}: the numbers comment lists no number")
        yield start, bool(m.group(1)), m.group(2), claims, problems
        i += 1


def json_value(report, key):
    """report['a']['b'][0] for the key a.b[0]; None when there is no such value."""
    value = report
    for part in re.findall(r"[^.\[\]]+|\[\d+\]", key):
        if part.startswith("["):
            index = int(part[1:-1])
            value = value[index] if isinstance(value, list) and index < len(value) else None
        else:
            value = value.get(part) if isinstance(value, dict) else None
        if value is None:
            return None
    return value


def as_written(value, written):
    """value rounded as the doc writes `written`: the same number of decimals."""
    decimals = len(written.split(".", 1)[1]) if "." in written else 0
    return f"{value:.{decimals}f}"


def numbers(args):
    root = pathlib.Path(args.root)
    if args.list:
        for doc in args.docs:
            path = pathlib.Path(doc)
            origin = path.resolve().relative_to(root.resolve()).as_posix()
            for line, slow, _, _, _ in numbers_comments(path):
                print(f"{origin}:{line}|{'slow' if slow else 'fast'}")
        return 0
    doc, line = args.at.rsplit(":", 1)
    path = root / doc
    for start, _, command, claims, problems in numbers_comments(path):
        if start != int(line):
            continue
        if problems:
            print("\n".join(problems))
            return 1
        argv = shlex.split(command)
        if argv[0] == "implicit":
            if not args.cli:
                print(f"{args.at}: the command needs the implicit tool, which this build has not")
                return 1
            argv[0] = args.cli
        result = subprocess.run(argv, capture_output=True, text=True, timeout=args.timeout,
                                cwd=root)
        if result.returncode != 0:
            print(f"{args.at}: '{command}' exited with {result.returncode}:\n{result.stderr}")
            return 1
        try:
            report = json.loads(result.stdout)
        except json.JSONDecodeError as e:
            print(f"{args.at}: '{command}' printed no JSON ({e}); a numbers comment's command "
                  f"must print JSON (add --json)")
            return 1
        wrong = 0
        for key, written in claims:
            value = json_value(report, key)
            if not isinstance(value, (int, float)) or isinstance(value, bool):
                print(f"{args.at}: '{command}' gives no number '{key}' (got {value!r})")
                wrong += 1
            elif as_written(value, written) != written:
                print(f"{args.at}: the doc says {key} = {written}, '{command}' gives {value!r} "
                      f"({as_written(value, written)} as the doc writes it)")
                wrong += 1
            else:
                print(f"{args.at}: {key} = {written} ok")
        return 1 if wrong else 0
    print(f"{args.at}: no numbers comment starts on that line")
    return 1


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command_name", required=True)
    p = sub.add_parser("extract")
    p.add_argument("--root", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--manifest", required=True)
    p.add_argument("docs", nargs="+")
    p = sub.add_parser("run")
    p.add_argument("--origin", required=True)
    p.add_argument("--expected", default="")
    p.add_argument("--tolerance", type=float, default=0.0)
    p.add_argument("--timeout", type=float, default=120.0)
    p.add_argument("--positive", action="append", default=[], metavar="KEY",
                   help="the program prints JSON whose number KEY must be > 0 (repeatable)")
    p.add_argument("command", nargs="+")
    p = sub.add_parser("numbers")
    p.add_argument("--root", required=True)
    p.add_argument("--cli", default="", help="the implicit executable the commands name")
    p.add_argument("--timeout", type=float, default=3600.0)
    p.add_argument("--list", action="store_true",
                   help="list the comments of the docs as FILE:LINE|fast or |slow")
    p.add_argument("--at", default="", help="FILE:LINE of the comment to check")
    p.add_argument("docs", nargs="*")
    for name in ("citations", "umbrella", "versions"):
        p = sub.add_parser(name)
        p.add_argument("--root", required=True)
    p.add_argument("--cli", default="", help="the implicit executable, whose --version is checked")
    args = parser.parse_args()
    if args.command_name == "extract":
        return extract(args) or 0
    return {"run": run, "citations": citations, "umbrella": umbrella, "versions": versions,
            "numbers": numbers}[args.command_name](args)


if __name__ == "__main__":
    sys.exit(main())
