#!/usr/bin/env python3
"""The include direction (shared/DESIGN.md; spec/backends.md R1-BKD-015), checked on every source.

fixedpoint <- spec <- format; fixedpoint <- spec <- solvers (the canonical numerical stages, generic over
their kernels, R1-SOL-001); format, solvers <- reference; format, solvers <- accel; backends/api <- spec;
each adapter <- its implementation; drivers (the pipeline binding, conformance) and consumers
(cli, tests, fuzz, bench) <- anything. An include against the direction is one line on stderr,
FILE:LINE: the include and the rule, and exit status 1.

  scripts/check-layering.py [ROOT]    check ROOT (default: the repository holding this script)
  scripts/check-layering.py --self-test   prove that a violation is caught and a clean tree passes
"""
import os
import re
import sys
import tempfile

# Where headers are found, as the build's include directories give them (relative to ROOT).
INCLUDE_ROOTS = ["fixedpoint/include", "spec/include", "format/include", "solvers/include", "reference/include",
                 "accel/cpu/include", "accel/vulkan/include", "backends/include",
                 "reference"]

# Adapters that wrap an implementation may include it (each adapter <- its implementation).
ADAPTER_IMPLEMENTATION = {
    "backends/adapters/reference_backend.cpp": {"reference"},
    "backends/adapters/stage_backend.hpp": {"reference"},  # the adapter over ReferenceStages
    # the cpu backend: accel/cpu's kernels in the solver the reference's stage list runs (R1-BKD-043)
    "backends/adapters/cpu_backend.cpp": {"reference", "accel", "solvers"},
    "backends/adapters/host_device.cpp": {"reference"},  # the trait over host memory: the reference's Clifford
    # the trait on accel/vulkan's context, det_exp's constants from the reference's Clifford
    "backends/adapters/vulkan_device.cpp": {"reference", "accel"},
    "backends/adapters/vulkan_adapters.hpp": {"accel"},  # the context the Vulkan device and backend share
    "backends/adapters/vulkan_passes.hpp": {"reference", "accel"},  # the backend's frame passes its tests call
    # the vulkan backend: accel/vulkan's frame passes, the cpu backend's kernels for its epoch stages
    "backends/adapters/vulkan_backend.cpp": {"reference", "accel", "solvers"},
}

# Layer of a file by its path, first match wins.
LAYER_OF = [
    ("fixedpoint/", "fixedpoint"),
    ("spec/", "spec"),
    ("format/", "format"),
    ("solvers/", "solvers"),
    ("reference/", "reference"),
    ("accel/", "accel"),
    ("backends/include/r1/backends/", "backends-api"),
    ("backends/registry.cpp", "backends-api"),
    ("backends/adapters/", "adapter"),
    ("backends/pipeline.cpp", "driver"),
    ("backends/conformance/", "driver"),
    ("backends/include/r1/conformance/", "driver"),
    ("cli/", "consumer"),
    ("viewer/", "consumer"),  # the web viewer's server and page: reads epochs through the reference
    ("tests/", "consumer"),
    ("fuzz/", "consumer"),
    ("bench/", "consumer"),
]

BELOW = {"fixedpoint": {"fixedpoint"}}
BELOW["spec"] = BELOW["fixedpoint"] | {"spec"}
BELOW["format"] = BELOW["spec"] | {"format"}
BELOW["solvers"] = BELOW["spec"] | {"solvers"}
BELOW["reference"] = BELOW["format"] | BELOW["solvers"] | {"reference"}
BELOW["accel"] = BELOW["format"] | BELOW["solvers"] | {"accel"}
BELOW["backends-api"] = BELOW["format"] | {"backends-api", "adapter"}
BELOW["adapter"] = BELOW["backends-api"]
BELOW["driver"] = BELOW["reference"] | {"backends-api", "adapter", "driver"}

SOURCE = re.compile(r"\.(cpp|hpp|h|inc|cpp\.in)$")
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')


def layer_of(rel):
    for prefix, layer in LAYER_OF:
        if rel == prefix or rel.startswith(prefix):
            return layer
    return None


def resolve(root, including_dir, target):
    """The included file's path relative to ROOT, or None (a system or third-party header)."""
    for base in [including_dir] + [os.path.join(root, r) for r in INCLUDE_ROOTS]:
        p = os.path.normpath(os.path.join(base, target))
        if os.path.isfile(p):
            rel = os.path.relpath(p, root)
            if not rel.startswith(".."):
                return rel.replace(os.sep, "/")
    return None


def check(root):
    problems = []
    for top in ["fixedpoint", "spec", "format", "solvers", "reference", "accel", "backends"]:
        for dirpath, dirnames, filenames in os.walk(os.path.join(root, top)):
            dirnames[:] = sorted(d for d in dirnames if not d.startswith("."))
            for name in sorted(filenames):
                if not SOURCE.search(name):
                    continue
                path = os.path.join(dirpath, name)
                rel = os.path.relpath(path, root).replace(os.sep, "/")
                layer = layer_of(rel)
                # Tests beside the code are consumers: they may reach anything (house style).
                if layer is None or name.endswith("_test.cpp") or "_test_" in name:
                    continue
                allowed = BELOW.get(layer, set()) | ADAPTER_IMPLEMENTATION.get(rel, set())
                with open(path, encoding="utf-8", errors="replace") as f:
                    for number, line in enumerate(f, 1):
                        m = INCLUDE.match(line)
                        if not m:
                            continue
                        target = resolve(root, dirpath, m.group(2))
                        if target is None:
                            continue
                        to = layer_of(target)
                        if to is None or to in allowed:
                            continue
                        problems.append(f"{rel}:{number}: includes \"{m.group(2)}\" ({to}), against the include "
                                        f"direction: {layer} may include only {', '.join(sorted(allowed))} "
                                        f"(shared/DESIGN.md, spec/backends.md R1-BKD-015)")
    return problems


def self_test():
    with tempfile.TemporaryDirectory() as root:
        def write(rel, text):
            p = os.path.join(root, rel)
            os.makedirs(os.path.dirname(p), exist_ok=True)
            with open(p, "w") as f:
                f.write(text)
        write("spec/include/r1/spec/epoch.hpp", "#pragma once\n")
        write("reference/include/r1/reference/epoch.hpp", '#include "r1/spec/epoch.hpp"\n')
        write("backends/include/r1/backends/backend.hpp", '#pragma once\n#include "r1/spec/epoch.hpp"\n#include <vector>\n')
        write("backends/adapters/reference_backend.cpp", '#include "r1/reference/epoch.hpp"\n')
        if check(root):
            print("self-test: a clean tree was rejected: " + "; ".join(check(root)), file=sys.stderr)
            return 1
        write("backends/include/r1/backends/backend.hpp",
              '#pragma once\n#include "r1/spec/epoch.hpp"\n#include "r1/reference/epoch.hpp"\n')
        write("spec/include/r1/spec/graph.hpp", '#pragma once\n\n  #  include <r1/reference/epoch.hpp>\n')
        found = check(root)
        want = ["backends/include/r1/backends/backend.hpp:3: includes \"r1/reference/epoch.hpp\" (reference)",
                "spec/include/r1/spec/graph.hpp:3: includes \"r1/reference/epoch.hpp\" (reference)"]
        for w in want:
            if not any(p.startswith(w) for p in found):
                print(f"self-test: the violation '{w}' was not reported (got: {found})", file=sys.stderr)
                return 1
        if len(found) != len(want):
            print(f"self-test: expected {len(want)} violations, got {found}", file=sys.stderr)
            return 1
    print("check-layering self-test: a bad include is caught with FILE:LINE, a clean tree passes")
    return 0


def main(argv):
    if len(argv) > 1 and argv[1] == "--self-test":
        return self_test()
    root = argv[1] if len(argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    problems = check(root)
    for p in problems:
        print(p, file=sys.stderr)
    if problems:
        return 1
    print("check-layering: every include follows the direction (shared/DESIGN.md)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
