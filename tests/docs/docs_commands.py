#!/usr/bin/env python3
"""The docs test (issue 40): every command README.md and docs/*.md show,
run as a user would type it, shortened where it would be long; it fails
when one exits with a usage or configuration error (exit 2) or names a
file that is not there.

What counts as a command: a line of a fenced block, or an inline `code`
span, that starts with `haptel`, `haptel-vehicle`, `scripts/` or
`build/bin/` (a `$ ` prompt and a trailing `# comment` dropped, `\` joining
lines). A line the programs print (`haptel run: ...`) is not one. What is
done with each:
- a synopsis (an upper-case placeholder such as FILE or STUDY.yaml,
  `[...]`, `a|b`, `...`, `<...>`; or a subcommand and its bare --options
  named in prose): each --option must be one its program's --help lists;
- a name (`haptel study power` in prose): the program and subcommand exist;
- a command: its --options are checked so, the repository files it names
  must exist, and it runs.

How it runs: the commands of one fenced block in turn (as a user types
them: what one writes, the next may read), in a folder of their own that
links config/, bench/, docs/, scripts/ and build/bin/ and holds runs/ (as
scripts/run's first lap leaves it), so nothing lands in the tree; `haptel`
is the build under test (its build/bin first on the PATH); no DISPLAY, so
runs are headless; a DDS domain held as the C++ tests hold theirs (the
docs' own `--domain 5` included), a free console port. Blocks run three at
once. A `haptel bench` gets `--smoke`. Each command runs until it exits or
says it is under way (a progress line), at most BUDGET_S: exit 0 or 1
(a lap cut short is 1) passes, and so does a command still running then
(haptel checks its options and files before it starts anything, exit 2
otherwise): it is stopped with SIGINT. A vehicle started in a block stays
up for the block's next commands. Exit 2, another exit code (3 lost, 4 not
recorded, 5 an output not written), or an output naming a missing file
fails. It also checks that `haptel --help` names every benchmark.

A command the suite cannot run (a real device, a person at a display,
minutes long, a file that is the reader's to write) is marked in the page,
with the reason, either for a whole fenced block or paragraph, on the line
before it:
    <!-- docs-test: skip, REASON -->
or for one line of a block, in its comment:
    haptel-vehicle --config config/vehicles/can-robot.yaml --can can0   # the robot (docs-test: skip, a CAN bus)
(`check` instead of `skip` reads better for a command that needs what an
earlier one made; both are not run.) The test lists each with its reason,
and still checks its --options. `scripts/*` commands are never run (they
build the tree or run this suite); their options are checked against the
script's text (scripts/run's: haptel run's --help).

usage: docs_commands.py REPO_ROOT BIN_DIR SCRATCH_DIR [--list] [--only SUBSTRING]
"""
import fcntl
import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor

BUDGET_S = 8.0          # a command still running after this has started: stopped, passes
BENCH_BUDGET_S = 8.0    # a bench's --smoke run: the same rule (bench smoke runs are the bench test's)
WORKERS = 3             # the commands mostly wait on spawned vehicles and DDS discovery
PREFIXES = ("haptel ", "haptel-vehicle", "scripts/", "build/bin/")
MARK = re.compile(r"<!--\s*docs-test:\s*(skip|check)\b[:,]?\s*(.*?)\s*-->")
MARK_IN_COMMENT = re.compile(r"docs-test:\s*(skip|check)\b[:,]?\s*([^)\]]*)")
FENCE = re.compile(r"^\s*(```|~~~)")
PLACEHOLDER = re.compile(r"(\b[A-Z][A-Z0-9_]{1,}\b(?![\-/])|\[|\]|\.\.\.|<[^>]*>|\w\|\w|…)")
MISSING = re.compile(r"(no such file|cannot open|does not exist|not found|no file)", re.IGNORECASE)


class Command:
    def __init__(self, page, line, text, inline, mark, reason, block):
        self.page, self.line, self.text = page, line, text
        self.inline, self.mark, self.reason = inline, mark, reason
        self.block = block  # (page, line of the fence): a block's commands run in turn, in one folder

    def where(self):
        return f"{self.page}:{self.line}"


def is_command(text):
    return text == "haptel" or text.startswith(PREFIXES)


def strip_comment(line):
    """The command without its trailing `# comment` (outside quotes)."""
    out, quote = [], None
    for i, c in enumerate(line):
        if quote:
            if c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c == "#" and (i == 0 or line[i - 1].isspace()):
            break
        out.append(c)
    return "".join(out).strip()


def extract(root):
    """Every command in README.md and docs/*.md, in page order."""
    pages = ["README.md"] + sorted(os.path.join("docs", p) for p in os.listdir(os.path.join(root, "docs"))
                                   if p.endswith(".md"))
    commands = []
    for page in pages:
        lines = open(os.path.join(root, page), encoding="utf-8").read().split("\n")
        fenced = False
        fence_at = 0
        mark = reason = None      # the pending marker
        marked_block = False      # the marker applies to this fenced block / paragraph
        joined, joined_at = "", 0
        for n, line in enumerate(lines, 1):
            m = MARK.search(line) if not fenced else None
            if m:
                mark, reason, marked_block = m.group(1), m.group(2) or "(no reason given)", False
                continue
            if FENCE.match(line):
                fenced = not fenced
                if fenced:
                    fence_at = n
                    marked_block = mark is not None
                else:
                    mark = reason = None
                    marked_block = False
                continue
            if fenced:
                text = line.strip()
                if text.startswith("$ "):
                    text = text[2:]
                if joined:
                    text, n = joined + " " + text, joined_at
                    joined = ""
                inline_mark = MARK_IN_COMMENT.search(text[len(strip_comment(text)):])
                text = strip_comment(text)
                if text.endswith("\\"):
                    joined, joined_at = text[:-1].strip(), n
                    continue
                if text.endswith("&"):
                    text = text[:-1].strip()
                if is_command(text):
                    line_mark, line_reason = (mark, reason) if marked_block else (None, None)
                    if inline_mark:
                        line_mark, line_reason = inline_mark.group(1), inline_mark.group(2).strip()
                    commands.append(Command(page, n, text, False, line_mark, line_reason, (page, fence_at)))
                continue
            if not line.strip():
                # A blank line ends a marked paragraph (one whose marker came before it).
                if marked_block:
                    mark = reason = None
                    marked_block = False
                continue
            if mark is not None and not marked_block:
                marked_block = True  # the marker's paragraph starts here
            for span in re.findall(r"`([^`]+)`", line):
                text = span.strip()
                if is_command(text):
                    commands.append(Command(page, n, text, True, mark if marked_block else None, reason,
                                            (page, n, text)))
    return commands


def synopsis(command):
    return PLACEHOLDER.search(command.text) is not None


def kind(command):
    """run, or for an inline span: synopsis (placeholders: options checked),
    name (a program or subcommand named in prose, no arguments: it must
    exist), message (a line the programs print, not a command: ignored)."""
    words = command.text.split()
    if any(w.endswith((":", ",")) for w in words[:3]):
        return "message"
    if synopsis(command):
        return "synopsis"
    if not command.inline:
        return "run"
    if all(re.fullmatch(r"[a-z][a-z0-9-]*", w) for w in words[1:]) or command.text.endswith("/") \
            or command.text.startswith("scripts/") and "." in words[0]:
        return "name"
    if all(re.fullmatch(r"--?[a-z][a-z0-9-]*|[a-z][a-z0-9-]*", w) for w in words[1:]):
        return "synopsis"  # a subcommand's option named in prose
    return "run"


# --- the static check: options against --help, files that must exist ---

HELP_CACHE = {}
CACHE_LOCK = threading.Lock()
KEY_LOCKS = {}


def once(cache, key, compute):
    """cache[key], computed once whatever the threads asking."""
    with CACHE_LOCK:
        lock = KEY_LOCKS.setdefault((id(cache), key), threading.Lock())
    with lock:
        if key not in cache:
            cache[key] = compute()
        return cache[key]


def program_and_sub(argv):
    """(the program's path, the subcommand words before the first option or argument)."""
    program = argv[0]
    words = []
    for a in argv[1:]:
        if not re.fullmatch(r"[a-z][a-z0-9-]*", a) or len(words) >= 2:
            break
        words.append(a)
    if os.path.basename(program) == "haptel-bench":
        words = ["bench"] + words
        program = os.path.join(os.path.dirname(program), "haptel")
    if words[:1] == ["bench"]:
        words = ["bench"]  # `haptel bench --help` gives every benchmark's options: one call for all
    return program, words


def help_text(binary, sub):
    def compute():
        # `haptel study run --help`, then `haptel study --help` ...: the nearest that answers.
        for k in range(len(sub), -1, -1):
            r = subprocess.run([binary] + sub[:k] + ["--help"], capture_output=True, text=True, timeout=60)
            if r.returncode == 0 and (r.stdout or r.stderr):
                return r.stdout + r.stderr
        return ""
    return once(HELP_CACHE, (binary, tuple(sub)), compute)


def resolve(argv, root, bin_dir):
    """argv with the program made absolute: `haptel` and build/bin/X from the build under test."""
    program = argv[0]
    if program.startswith("build/bin/"):
        program = os.path.join(bin_dir, program[len("build/bin/"):])
    elif "/" not in program:
        program = os.path.join(bin_dir, program)
    else:
        program = os.path.join(root, program)
    return [program] + argv[1:]


def static_problems(command, root, bin_dir):
    """What is wrong with the command without running it: options its
    program does not take, files it names that are not there."""
    problems = []
    try:
        argv = shlex.split(command.text)
    except ValueError as e:
        return [f"cannot split: {e}"]
    argv = resolve(argv, root, bin_dir)
    program = argv[0]
    if not os.path.exists(program):
        return [f"no program {program}"]
    if argv[0].startswith(os.path.join(root, "scripts")):
        text = open(program, encoding="utf-8").read()
        if "haptel_build product" in text and "exec" in text:  # scripts/run: its options are haptel run's
            text += help_text(os.path.join(bin_dir, "haptel"), ["run"])
    else:
        help_program, sub = program_and_sub(argv)
        text = help_text(help_program, sub)
    for a in argv[1:]:
        if a.startswith("--") and a != "--help":
            option = a.split("=", 1)[0]
            if not re.search(re.escape(option) + r"(?![\w-])", text):
                problems.append(f"option {option} is not in its --help")
    if synopsis(command) or command.mark == "skip":
        return problems  # a synopsis's paths are placeholders; a skipped one's may be yours to write
    for a in argv[1:]:
        for path in re.split(r"[=,]", a):
            if re.match(r"^(config|docs|bench|scripts)/", path) and not os.path.exists(os.path.join(root, path)):
                problems.append(f"no file {path}")
    return problems


NAME_CACHE = {}


def name_problems(command, root, bin_dir):
    """A program or subcommand named in prose: it must be there."""
    return once(NAME_CACHE, command.text, lambda: named_problems(command, root, bin_dir))


def named_problems(command, root, bin_dir):
    words = command.text.split()
    if words[0].endswith("/"):
        path = os.path.join(bin_dir if words[0] == "build/bin/" else root, "" if words[0] == "build/bin/" else words[0])
        return [] if os.path.isdir(path) else [f"no folder {words[0]}"]
    program = resolve(words[:1], root, bin_dir)[0]
    if not os.path.exists(program):
        return [f"no program {words[0]}"]
    if words[0].startswith("scripts/") or len(words) == 1:
        return []
    # Named in the program's own usage (haptel --help lists its commands, haptel bench --help its
    # benchmarks): there, without running each one's --help.
    if words[1:2] == ["bench"] and len(words) > 2:
        return [] if re.search(r"^  haptel bench " + re.escape(words[2]) + r"\b", help_text(program, ["bench"]),
                               re.MULTILINE) else [f"haptel bench --help lists no benchmark '{words[2]}'"]
    for k in range(1, len(words)):
        if re.search(r"\b" + re.escape(" ".join(words[k:])) + r"\b", help_text(program, words[1:k])):
            return []
    r = subprocess.run([program] + words[1:] + ["--help"], capture_output=True, text=True, timeout=30)
    if r.returncode != 0:
        return [f"`{command.text} --help` exits {r.returncode}: {(r.stdout + r.stderr).strip()[:200]}"]
    return []


def usage_problems(bin_dir):
    """`haptel --help` names every benchmark `haptel bench --help` lists
    (issue 40: passivity, video and fleet were missing)."""
    haptel = os.path.join(bin_dir, "haptel")
    listed = re.findall(r"^  haptel bench ([a-z0-9-]+)", help_text(haptel, ["bench"]), re.MULTILINE)
    if not listed:
        return ["haptel bench --help lists no benchmark"]
    usage = help_text(haptel, [])
    return [f"haptel --help does not name the benchmark '{b}' (haptel bench --help lists it)"
            for b in listed if not re.search(r"\b" + re.escape(b) + r"\b", usage)]


# --- running ---

def shortened(argv):
    """The command as the suite runs it: a bench's smoke run."""
    if len(argv) > 2 and os.path.basename(argv[0]) in ("haptel", "haptel-bench") and "bench" in argv[:2]:
        if "--smoke" not in argv:
            argv = argv + ["--smoke"]
    return argv


def prepare_scratch(scratch):
    if os.path.exists(scratch):
        shutil.rmtree(scratch)
    os.makedirs(scratch)


SERVERS = ("haptel-vehicle", "haptel-device-server")
# A line that says the command is under way: stop it there (no need to wait out the budget).
STARTED = re.compile(r"(\d+\.\d s +\S+ +lap|fleet: driving|trial \d+|serving|listening|vehicle '[^']*' (up|ready))")


class Domain:
    """A DDS domain held for a block, as the C++ tests hold theirs
    (tests/support/test_env.hpp, UniqueDomain: an exclusive lock on a file
    of its own under the temporary folder), so nothing else hears it."""

    def __init__(self, salt):
        folder = os.path.join(tempfile.gettempdir(), "haptel-test-domains")
        os.makedirs(folder, exist_ok=True)
        for k in range(230):
            domain = 1 + (os.getpid() * 7 + salt + k) % 230
            fd = os.open(os.path.join(folder, str(domain)), os.O_CREAT | os.O_RDONLY | os.O_CLOEXEC, 0o666)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                os.close(fd)
                continue
            self.fd, self.domain = fd, str(domain)
            return
        raise RuntimeError("every DDS domain 1..230 is held by another test process")

    def release(self):
        os.close(self.fd)  # the lock goes with it


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def as_run(command, root, bin_dir, domain):
    """The argv the suite runs for `command`: the build's programs, a bench's
    smoke run, this block's DDS domain (the docs' own `--domain 5` too: the
    suite's other tests hold domains of their own) and a free console port."""
    argv = shortened(resolve(shlex.split(command.text), root, bin_dir))
    program = os.path.basename(argv[0])
    help_program, sub = program_and_sub(argv)
    text = help_text(help_program, sub) if program.startswith("haptel") else ""
    if "--domain" in argv:
        argv[argv.index("--domain") + 1] = domain
    elif re.search(r"--domain\b", text) and "bench" not in sub:
        argv += ["--domain", domain]
    if "--port" not in argv and re.search(r"--port\b", text) and sub[:2] == ["study", "run"] and \
            "--simulated-time" not in argv:
        argv += ["--port", str(free_port())]
    return argv


def finish(process, budget, out_lines):
    """Waits up to `budget` s or until the command says it has started; then
    stops it (its process group). Returns (exit code, stopped while running)."""
    deadline = time.monotonic() + budget
    while process.poll() is None and time.monotonic() < deadline:
        if any(STARTED.search(l) for l in out_lines):
            break
        time.sleep(0.1)
    if process.poll() is not None:
        return process.returncode, False
    stop(process)
    return process.returncode, True


def stop(process):
    try:
        os.killpg(process.pid, signal.SIGINT)
        process.wait(timeout=20)
    except (subprocess.TimeoutExpired, ProcessLookupError):
        try:
            os.killpg(process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        process.wait()


def start(argv, cwd, env):
    lines = []
    process = subprocess.Popen(argv, cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, start_new_session=True)

    def read():
        for line in process.stdout:
            lines.append(line.rstrip("\n"))
    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    return process, lines, reader


def verdict(code, stopped, lines, took, budget):
    tail = "\n      ".join(lines[-6:])
    if stopped:
        return True, f"started; stopped after {took:.1f} s"
    if code == 2:
        return False, f"exit 2 (a usage or configuration error) in {took:.1f} s:\n      {tail}"
    if code not in (0, 1):
        return False, f"exit {code} in {took:.1f} s:\n      {tail}"
    missing = [l for l in lines if MISSING.search(l) and "warning" not in l.lower()]
    if missing:
        return False, f"exit {code}, but a file is missing:\n      {missing[0]}"
    return True, f"exit {code} in {took:.1f} s"


def run_block(index, block, root, bin_dir, scratch):
    """Runs a block's commands in turn in a folder of its own (as a user
    types them: what one writes, the next may read); a vehicle or device
    server started in it stays up until the block ends. [(command, passed, what)]."""
    cwd = os.path.join(scratch, f"b{index:03d}")
    os.makedirs(cwd)
    for name in ("config", "bench", "docs", "scripts", "haptics", "calibration"):
        if os.path.exists(os.path.join(root, name)):
            os.symlink(os.path.join(root, name), os.path.join(cwd, name))
    os.makedirs(os.path.join(cwd, "build"))
    os.makedirs(os.path.join(cwd, "runs"))  # as scripts/run's first lap leaves it
    os.symlink(bin_dir, os.path.join(cwd, "build", "bin"))
    env = dict(os.environ)
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    env["PATH"] = bin_dir + os.pathsep + env.get("PATH", "")
    held = Domain(index)
    domain = held.domain
    results, servers = [], []
    try:
        for i, command in enumerate(block):
            argv = as_run(command, root, bin_dir, domain)
            budget = BENCH_BUDGET_S if "bench" in argv[:3] else BUDGET_S
            t0 = time.monotonic()
            process, lines, reader = start(argv, cwd, env)
            if os.path.basename(argv[0]) in SERVERS and i + 1 < len(block):
                # A server the next commands use: up for the rest of the block.
                time.sleep(1.0)
                if process.poll() is None:
                    servers.append(process)
                    results.append((command, True, "started (a server the block's next commands use)"))
                    continue
            code, stopped = finish(process, budget, lines)
            reader.join(timeout=5)
            results.append((command,) + verdict(code, stopped, lines, time.monotonic() - t0, budget))
    finally:
        for process in servers:
            stop(process)
        held.release()
    return results


def main():
    args = sys.argv[1:]
    listing = "--list" in args
    only = None
    if "--only" in args:
        only = args[args.index("--only") + 1]
        args = [a for a in args if a not in ("--only", only)]
    args = [a for a in args if a != "--list"]
    root, bin_dir, scratch = (os.path.abspath(a) for a in args[:3])
    commands = extract(root)
    if only:
        commands = [c for c in commands if only in c.text]
    if listing:
        for c in commands:
            print(f"{c.where():28} {c.mark or kind(c):8} {c.text}")
        return 0
    prepare_scratch(scratch)
    failures, skipped, ran = [], [], []
    to_run = []
    seen = set()
    def check(c):
        k = kind(c)
        if k == "message":
            return []
        return name_problems(c, root, bin_dir) if k == "name" else static_problems(c, root, bin_dir)

    if not only and sum(1 for c in commands if kind(c) == "run") < 20:
        failures.append(f"only {len(commands)} commands found in README.md and docs/: the extraction is broken")
    failures += usage_problems(bin_dir)
    t0 = time.monotonic()
    with ThreadPoolExecutor(max_workers=4) as pool:  # mostly --help calls, cached
        for c, problems in zip(commands, pool.map(check, commands)):
            failures += [f"{c.where()}: {c.text}\n      {p}" for p in problems]
    checked_s = time.monotonic() - t0
    for c in commands:
        k = kind(c)
        if k in ("message", "name", "synopsis"):
            continue
        if c.text.startswith("scripts/"):
            skipped.append((c, "a script that builds the tree or runs this suite"))
            continue
        if c.mark:
            skipped.append((c, f"{c.mark}: {c.reason}"))
            continue
        if c.text in seen:
            continue  # the same command on another page: run once
        seen.add(c.text)
        to_run.append(c)
    blocks = {}
    for c in to_run:
        blocks.setdefault(c.block, []).append(c)
    t0 = time.monotonic()
    with ThreadPoolExecutor(max_workers=WORKERS) as pool:
        results = list(pool.map(lambda ib: run_block(ib[0], ib[1], root, bin_dir, scratch),
                                enumerate(blocks.values())))
    for block_results in results:
        for c, ok, what in block_results:
            ran.append(f"{'ok  ' if ok else 'FAIL'} {c.where()}: {c.text}\n      {what}")
            if not ok:
                failures.append(f"{c.where()}: {c.text}\n      {what}")
    print(f"docs test: {len(commands)} commands in README.md and docs/, each checked against its "
          f"--help in {checked_s:.0f} s; ran {len(to_run)} in {time.monotonic() - t0:.0f} s "
          f"({len(blocks)} blocks, {WORKERS} at once)")
    for line in ran:
        print("  " + line)
    print(f"not run here ({len(skipped)}; options and files checked):")
    for c, why in skipped:
        print(f"  {c.where()}: {c.text}\n      {why}")
    if failures:
        print(f"\n{len(failures)} FAILED:")
        for f in failures:
            print("  " + f)
        return 1
    print("docs test: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
