#!/usr/bin/env python3
"""Every source of the build compiles for aarch64 (spec/backends.md R1-BKD-045), checked on an x86-64 host.

Each source of r1's libraries and commands in build/compile_commands.json (the x86-64 build's
exact flags; with --all the tests, benchmarks and fuzz targets too) is compiled again with
Debian's aarch64 cross compiler, syntax and types only (-fsyntax-only: no object code, no link).
The default leaves the test sources out to keep `make test` inside its budget (about 4 minutes
for all 223 sources on two cores, against about 2 for the libraries' and commands'); the code
that differs per architecture lives in the libraries.
The cross compiler brings its own C and C++ library headers; the libraries' headers (TBB, Boost,
Eigen, ...) are the host's, found after the compiler's own in /usr/include and, for the few that
differ per architecture (OpenSSL's configuration header: LP64 on both), the host's multiarch
directory. A failing file is one line on stderr, FILE: its first error, and exit status 1.

  scripts/check-aarch64.py [BUILD_DIR] [-j N] [--all]    default build/, N = the CPU count

On an aarch64 host the native build is the check, and without the cross compiler there is nothing
to check with: both say so on one line and exit 0 (install-deps.sh installs it on x86-64 hosts).
"""
import concurrent.futures
import json
import os
import platform
import shlex
import shutil
import subprocess
import sys

CROSS = "aarch64-linux-gnu-g++"
HOST_HEADERS = ["/usr/include", "/usr/include/x86_64-linux-gnu"]


def cross_command(entry):
    """The entry's compile command for the cross compiler, syntax only, no outputs."""
    args = shlex.split(entry["command"]) if "command" in entry else list(entry["arguments"])
    i = 0
    while os.path.basename(args[i]) == "ccache":  # the compiler comes after any launcher
        i += 1
    out = [CROSS]
    skip = False
    for a in args[i + 1:]:
        if skip:
            skip = False
            continue
        if a in ("-o", "-MF", "-MT", "-MQ"):
            skip = True
            continue
        if a in ("-c", "-MD", "-MMD"):
            continue
        out.append(a)
    out.append("-fsyntax-only")
    for d in HOST_HEADERS:
        out += ["-idirafter", d]
    return out


def first_error(stderr):
    for line in stderr.splitlines():
        if "error" in line:
            return line.strip()
    lines = stderr.strip().splitlines()
    return lines[-1] if lines else "failed without a message"


def main(argv):
    build = "build"
    jobs = os.cpu_count() or 1
    everything = False
    rest = list(argv)
    while rest:
        a = rest.pop(0)
        if a == "-j" and rest:
            jobs = max(1, int(rest.pop(0)))
        elif a == "--all":
            everything = True
        elif a.startswith("-"):
            print(f"check-aarch64: unknown option {a}", file=sys.stderr)
            return 2
        else:
            build = a
    if platform.machine() in ("aarch64", "arm64"):
        print("check-aarch64: this host is aarch64; its own build is the check")
        return 0
    if shutil.which(CROSS) is None:
        print(f"check-aarch64: {CROSS} not found (scripts/install-deps.sh installs it); nothing checked")
        return 0
    db = os.path.join(build, "compile_commands.json")
    try:
        with open(db) as f:
            entries = json.load(f)
    except (OSError, ValueError) as e:
        print(f"check-aarch64: {db}: {e}", file=sys.stderr)
        return 2
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    # Sources of the project only (generated files and other trees under build/ are not ours).
    def ours(entry):
        rel = os.path.relpath(os.path.join(entry["directory"], entry["file"]), root)
        if rel.startswith("..") or rel.split(os.sep)[0].startswith("build"):
            return False
        if everything:
            return True
        test_code = rel.split(os.sep)[0] in ("tests", "bench", "fuzz") or rel.endswith("_test.cpp") \
            or os.path.basename(rel).startswith("test_")
        return not test_code
    entries = [e for e in entries if ours(e)]

    def check(entry):
        r = subprocess.run(cross_command(entry), cwd=entry["directory"], capture_output=True, text=True)
        return entry["file"], r.returncode, r.stderr

    bad = 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        for path, rc, err in pool.map(check, entries):
            if rc != 0:
                bad += 1
                print(f"{os.path.relpath(path, root)}: {first_error(err)}", file=sys.stderr)
    print(f"check-aarch64: {len(entries) - bad} of {len(entries)} sources compile for aarch64")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
