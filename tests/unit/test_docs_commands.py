"""Every command line in the docs parses, so that none can rot (issue 67).

The command lines of README.md and docs/*.md (shell code blocks, indented code blocks and inline code) are
taken apart and checked without running anything:

- ``fvdem ...`` (also ``.venv/bin/fvdem``, ``python -m fvdem``) is parsed by the CLI's own parser,
  ``fvdem.cli.make_parser``; where it names a case file under ``cases/`` the case is loaded with its
  ``--set`` overrides (a renamed key is caught), and a study file under ``studies/`` is loaded with its
  ``--cluster`` file and ``--only`` run names;
- ``python tools/X.py ...`` must name an existing tool, and is parsed by the tool's own parser (its ``main``,
  stopped right after ``parse_args``);
- ``make X`` must name a target of the Makefile;
- an inline ``--set K=V ...`` is parsed as the options of ``fvdem run``.

docs/cli.md must list every command and option of the parser, and links between the docs must resolve.
A failure names the file and line of the command.
"""
from __future__ import annotations

import argparse
import contextlib
import importlib.util
import inspect
import io
import itertools
import re
import shlex
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from paths import ROOT

DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
SHELL_FENCES = {"", "sh", "bash", "shell", "console", "text"}
WRAPPERS = {"srun", "nohup", "setsid", "time", "env", "exec", "sudo", "timeout", "mpirun"}
SEPARATORS = {"|", "||", "&&", ";", "&"}

# Command lines known not to parse, in files rewritten by other work: file -> {a substring of the command: why}.
# Each still has to fail (so the entry is dropped once fixed): the file's test is then reported as xfail.
KNOWN_BROKEN: dict[str, dict[str, str]] = {}


@dataclass(frozen=True)
class Command:
    path: Path
    line: int
    text: str
    inline: bool

    def where(self) -> str:
        return f"{self.path.relative_to(ROOT)}:{self.line}"


# ---------------------------------------------------------------------------------------------- extraction

def commands(path: Path) -> list[Command]:
    """The candidate command lines of a Markdown file, with their line numbers (1-based)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    found: list[Command] = []
    prose: list[tuple[int, str]] = []  # (line number, text) of the lines outside fenced blocks
    fence, fence_lang, pending, pending_line = None, "", "", 0
    for number, line in enumerate(lines, 1):
        stripped = line.strip()
        marker = re.match(r"^\s*(```+|~~~+)\s*([\w+-]*)", line)
        if fence is None and marker:
            fence, fence_lang = marker.group(1), marker.group(2).lower()
            prose.append((number, ""))
            continue
        if fence is not None:
            if stripped.startswith(fence) and stripped.strip("`~") == "":
                fence = None
            elif fence_lang in SHELL_FENCES:
                text = stripped[2:] if stripped.startswith("$ ") else stripped
                if pending:
                    text, number_of = pending + " " + text, pending_line
                else:
                    number_of = number
                if text.endswith("\\"):
                    pending, pending_line = text[:-1], number_of
                    continue
                pending = ""
                if text:
                    found.append(Command(path, number_of, text, inline=False))
            prose.append((number, ""))
            continue
        if line.startswith("    ") and not line.startswith("    -") and _starts_a_command(stripped):
            found.append(Command(path, number, stripped, inline=False))
            prose.append((number, ""))
            continue
        prose.append((number, line))
    found.extend(_inline(path, prose))
    return found


def _inline(path: Path, prose: list[tuple[int, str]]) -> list[Command]:
    """Inline code spans that start with a command, paragraph by paragraph (a span may wrap a line)."""
    found = []
    paragraph: list[tuple[int, str]] = []
    for number, line in [*prose, (0, "")]:
        if line.strip():
            paragraph.append((number, line))
            continue
        if paragraph:
            text = "\n".join(text for _, text in paragraph)
            for span in re.finditer(r"(`+)(.+?)\1", text, flags=re.S):
                code = " ".join(span.group(2).split()).replace("\\|", "|")
                if _starts_a_command(code) or re.match(r"--set\s+\S+=", code):
                    line_number = paragraph[text.count("\n", 0, span.start())][0]
                    found.append(Command(path, line_number, code, inline=True))
        paragraph = []
    return found


def _starts_a_command(text: str) -> bool:
    first = _words(text)[:1]
    return bool(first) and _program(first[0], _words(text)[1:]) is not None


def _words(text: str) -> list[str]:
    text = re.sub(r"<[^<>]*>", lambda m: m.group(0).replace(" ", "_"), text)       # <this folder>: one word
    text = re.sub(r"\[(-[^\[\]]*)\]", r"\1", text)                                  # [--quick]: optional
    try:
        return shlex.split(text, comments=True)
    except ValueError:
        return text.split()


def _program(word: str, rest: list[str]) -> str | None:
    name = word.rsplit("/", 1)[-1]
    if name == "fvdem":
        return "fvdem"
    if re.fullmatch(r"python(3(\.\d+)?)?", name) and rest:
        if rest[:2] == ["-m", "fvdem"]:
            return "fvdem"
        if re.fullmatch(r"(\./)?tools/[\w./-]+\.py", rest[0]):
            return "tool"
        return None
    if name == "make" and word == "make":
        return "make"
    if re.fullmatch(r"(\./)?tools/\w+\.py", word):
        return "tool-path"
    return None


def invocations(command: Command) -> list[tuple[str, list[str]]]:
    """``(program, argv)`` of each command in a line (``a && b | c`` is three), argv without the program."""
    if command.inline and command.text.startswith("--set"):
        return [("fvdem", ["run", "CASE.toml", *_words(command.text)])]
    words = _words(command.text)
    segments, segment = [], []
    skip = False
    for word in words:
        if skip:
            skip = False
            continue
        if word in SEPARATORS:
            segments.append(segment)
            segment = []
        elif re.fullmatch(r"\d?>>?|&>", word):                     # a redirection: drop it and its target
            skip = True
        elif re.fullmatch(r"\d?>>?\S+|\d>&\d|&>\S+", word):
            continue
        else:
            segment.append(word)
    segments.append(segment)
    found = []
    for segment in segments:
        while segment and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*=.*", segment[0]):  # VAR=value before a command
            segment = segment[1:]
        if segment and segment[0].rsplit("/", 1)[-1] in WRAPPERS:
            starts = [k for k, word in enumerate(segment) if _program(word, segment[k + 1:])]
            segment = segment[starts[0]:] if starts else []
        if not segment:
            continue
        program = _program(segment[0], segment[1:])
        if program == "fvdem":
            found.append(("fvdem", segment[3:] if segment[1:3] == ["-m", "fvdem"] else segment[1:]))
        elif program == "tool":
            found.append(("tool", segment[1:]))
        elif program == "tool-path":
            found.append(("tool", segment))
        elif program == "make":
            found.append(("make", segment[1:]))
    return found


# ------------------------------------------------------------------------------------------------- checks

class _Parsed(Exception):
    """Raised by the patched ``parse_args``: the arguments parsed, run nothing."""

    def __init__(self, namespace):
        super().__init__("parsed")
        self.namespace = namespace


def _alternatives(argv: list[str]) -> list[list[str]]:
    """``--json-schema case|study`` stands for two command lines."""
    choices = [word.split("|") if "|" in word.strip("|") else [word] for word in argv]
    return [list(combo) for combo in itertools.islice(itertools.product(*choices), 16)]


@pytest.fixture(scope="module")
def parser_checks():
    """The fvdem parser with the machine taken out of its types: a thread count up to any number of cores, and
    ``--until`` dates judged against 1970 (their form is what is checked, not whether they have passed)."""
    from fvdem import cli
    from fvdem.study import cluster
    patch = pytest.MonkeyPatch()
    patch.setattr(cli, "cores", lambda: 1024)
    real_until = cluster.until_epoch
    patch.setattr(cluster, "until_epoch", lambda text, now=None: real_until(text, now=0.0))
    yield cli.make_parser()
    patch.undo()


def _parse_error(parse, argv: list[str], inline: bool):
    """``(namespace, None)`` or ``(None, the parser's message)``; a placeholder in capitals (``--drag LAW``,
    ``--aspect-ratio A``) is taken for a value of the right kind, and an inline mention of an option without
    the command's positional arguments (`fvdem study --status`) is given placeholders for them."""
    error = io.StringIO()
    try:
        with contextlib.redirect_stderr(error), contextlib.redirect_stdout(io.StringIO()):
            return parse(argv), None
    except SystemExit as exc:
        if exc.code == 0:  # --version, --help
            return None, None
        message = (error.getvalue().strip().splitlines() or ["does not parse"])[-1]
    placeholder = re.search(r"'([A-Z][A-Z0-9_]*)'", message)
    if placeholder and placeholder.group(1) in argv:
        return None, None
    required = re.search(r"arguments are required: (.*)$", message)
    if inline and required and "X" not in argv:
        return _parse_error(parse, [*argv, *["X"] * len(required.group(1).split(", "))], inline)
    return None, message


def check_fvdem(parser, argv: list[str], inline: bool) -> str | None:
    """None, or why ``fvdem ARGV`` is wrong."""
    commands_ = parser._subparsers._group_actions[0].choices
    if inline and len(argv) <= 1 and not any(a.startswith("-") for a in argv):
        return None if not argv or argv[0] in commands_ else f"no fvdem command {argv[0]!r}"  # a mention
    for variant in _alternatives(argv):
        namespace, message = _parse_error(parser.parse_args, variant, inline)
        if message:
            return message
        problem = _check_files(namespace) if namespace is not None else None
        if problem:
            return problem
    return None


def _repo_file(text: str | None, folder: str) -> Path | None:
    """The repository file a command names under ``cases/`` or ``studies/`` (None for placeholders)."""
    if not text or not text.startswith(folder + "/") or any(c in text for c in "*?<>$"):
        return None
    return ROOT / text


def _check_files(namespace) -> str | None:
    """The cheap checks behind a parsed command: its case or study file exists and loads."""
    from fvdem.errors import CaseError
    command = namespace.command
    try:
        if command in ("run", "check"):
            case = _repo_file(namespace.case, "cases")
            if case is not None:
                if not case.exists():
                    return f"no case file {namespace.case}"
                from fvdem.case import load_case, parse_override
                load_case(case, dict(parse_override(text) for text in namespace.set or []))
        elif command == "study":
            study_file = _repo_file(namespace.study, "studies")
            if study_file is not None:
                if not study_file.exists():
                    return f"no study file {namespace.study}"
                from fvdem.study import load_study
                study = load_study(study_file, namespace.out or str(ROOT / "runs" / "never-written"))
                unknown = set(namespace.only or []) - {run.name for run in study.runs}
                if unknown:
                    return f"--only: no such runs in {namespace.study}: {sorted(unknown)}"
            cluster_file = _repo_file(namespace.cluster, "studies")
            if namespace.cluster and cluster_file is not None:
                from fvdem.study import load_cluster
                load_cluster(cluster_file)
    except CaseError as exc:
        return "invalid: " + "; ".join(exc.problems)
    return None


_TOOLS: dict[Path, object] = {}


def check_tool(argv: list[str], inline: bool) -> str | None:
    """None, or why ``python TOOL ARGS`` is wrong: the tool must exist and its own parser take the arguments."""
    relative = argv[0].removeprefix("./")
    path = ROOT / relative
    if not path.is_file():
        return f"no tool {relative}"
    if inline and len(argv) == 1:
        return None  # a mention of the tool
    if path not in _TOOLS:
        sys.path.insert(0, str(path.parent))
        try:
            spec = importlib.util.spec_from_file_location(f"_docs_tool_{path.stem}", path)
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
        finally:
            sys.path.remove(str(path.parent))
        _TOOLS[path] = module
    main = getattr(_TOOLS[path], "main", None)
    if main is None:
        return None  # nothing to parse with
    real_parse = argparse.ArgumentParser.parse_args

    def parse_only(self, args=None, namespace=None):
        raise _Parsed(real_parse(self, args, namespace))

    def parse(variant):
        patch = pytest.MonkeyPatch()
        patch.setattr(argparse.ArgumentParser, "parse_args", parse_only)
        patch.setattr(sys, "argv", [str(path), *variant])
        try:
            main(variant) if inspect.signature(main).parameters else main()
        except _Parsed as parsed:
            return parsed.namespace
        finally:
            patch.undo()
        raise AssertionError(f"{relative}: main() did not reach parse_args")

    for variant in _alternatives(argv[1:]):
        _, message = _parse_error(parse, variant, inline)
        if message:
            return message
    return None


def make_targets() -> set[str]:
    text = (ROOT / "Makefile").read_text()
    return {m.group(1) for m in re.finditer(r"^([A-Za-z][\w.-]*)\s*:(?!=)", text, flags=re.M)}


def check_make(argv: list[str]) -> str | None:
    targets = [word for word in argv if not word.startswith("-") and "=" not in word]
    missing = [t for t in targets if t not in make_targets()]
    return f"no Makefile target {missing[0]!r}" if missing else None


def problems(parser, path: Path) -> list[tuple[Command, str]]:
    found = []
    for command in commands(path):
        for program, argv in invocations(command):
            if program == "fvdem":
                problem = check_fvdem(parser, argv, command.inline)
            elif program == "tool":
                problem = check_tool(argv, command.inline)
            else:
                problem = check_make(argv)
            if problem:
                found.append((command, problem))
    return found


# -------------------------------------------------------------------------------------------------- tests

@pytest.mark.parametrize("path", DOCS, ids=[str(p.relative_to(ROOT)) for p in DOCS])
def test_every_command_line_in_the_docs_parses(path, parser_checks):
    known = KNOWN_BROKEN.get(str(path.relative_to(ROOT)), {})
    found = problems(parser_checks, path)
    unknown = [(c, why) for c, why in found if not any(k in c.text for k in known)]
    assert not unknown, "command lines that do not parse:\n" + "\n".join(
        f"  {c.where()}: {c.text}\n    -> {why}" for c, why in unknown)
    if found:
        pytest.xfail("known: " + "; ".join(
            f"{c.where()}: {c.text} ({next(v for k, v in known.items() if k in c.text)})" for c, _ in found))
    stale = [k for k in known if not any(k in c.text for c, _ in found)]
    assert not stale, f"KNOWN_BROKEN entries of {path.name} that now parse (remove them): {stale}"


def test_the_docs_hold_command_lines_to_check():
    """The extraction finds what it should (a regression in it would make the test above pass vacuously)."""
    by_file = {p.name: [i for c in commands(p) for i in invocations(c)] for p in DOCS}
    assert sum(1 for program, _ in by_file["README.md"] if program == "make") >= 2
    assert sum(1 for program, _ in by_file["cli.md"] if program == "fvdem") >= 30
    assert sum(1 for program, _ in by_file["cli.md"] if program == "tool") >= 9
    assert sum(1 for program, _ in by_file["tutorial.md"] if program == "fvdem") >= 10


def test_a_broken_command_line_is_reported_with_its_file_and_line(tmp_path, parser_checks, monkeypatch):
    """Each kind of rot is caught at its line: several values after one --set, a misspelt command, a tool that
    is not there, a make target that is not there, a misspelt option (inline), --set spanning two lines; a
    date that has passed and more threads than this machine has are the machine's business, not the docs'."""
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    (tmp_path / "tools").mkdir()
    (tmp_path / "Makefile").write_text("demo:\n\techo\n")
    page = tmp_path / "page.md"
    page.write_text("# A page\n\n```sh\nfvdem run x.toml --set a=1 b=2\nfvdem studdy s.toml\n"
                    "python tools/nope.py --json\nmake demo && make nothing\n"
                    "fvdem study s.toml --out d --until 2026-12-05T04:45 && fvdem run x.toml --threads 64\n```\n\n"
                    "Inline: `fvdem run x.toml --treads 2`, a mention of `fvdem study`, and\n"
                    "`--set time.end=1 time.dem_step=1e-5` over a line.\n")
    found = {(c.line, why.split(":")[0]) for c, why in problems(parser_checks, page)}
    lines = sorted(line for line, _ in found)
    assert lines == [4, 5, 6, 7, 11, 12], found


def test_the_cli_reference_lists_every_command_and_option(parser_checks):
    """docs/cli.md has a section per fvdem command naming each of its options (from the parser itself)."""
    text = (ROOT / "docs" / "cli.md").read_text()
    sections = dict(re.findall(r"^## fvdem (\w+)\n(.*?)(?=^## |\Z)", text, flags=re.M | re.S))
    missing = []
    for name, sub in parser_checks._subparsers._group_actions[0].choices.items():
        if name not in sections:
            missing.append(f"## fvdem {name}")
            continue
        for action in sub._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            names = [s for s in action.option_strings if s.startswith("--")] or [action.dest]
            if not any(f"`{n}" in sections[name] for n in names):
                missing.append(f"fvdem {name} {names[0]}")
    assert not missing, f"docs/cli.md lacks: {missing}"


def _anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation but hyphens dropped, spaces as hyphens."""
    text = re.sub(r"[`*]", "", heading.strip().lower())
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


@pytest.mark.parametrize("path", DOCS, ids=[str(p.relative_to(ROOT)) for p in DOCS])
def test_links_between_the_docs_resolve(path):
    text = re.sub(r"```.*?```", "", path.read_text(encoding="utf-8"), flags=re.S)
    broken = []
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"[a-z]+:", target):
            continue
        file_part, _, anchor = target.partition("#")
        linked = (path.parent / file_part).resolve() if file_part else path
        if not linked.exists():
            broken.append(target)
        elif anchor and linked.suffix == ".md":
            headings = re.findall(r"^#+\s+(.*)$", linked.read_text(encoding="utf-8"), flags=re.M)
            if anchor not in {_anchor(h) for h in headings}:
                broken.append(target)
    assert not broken, f"{path.relative_to(ROOT)}: links that lead nowhere: {broken}"
