#!/usr/bin/python3
"""A real graph from a Debian package database: one link from each package to each package it
depends on (Depends and Pre-Depends; of alternatives `a | b` the first), as a TSV edge list that
`r1 epoch` reads. Usage:

    scripts/deb-deps-graph.py [STATUS_OR_PACKAGES_FILE] > deps.tsv

Default input: /var/lib/dpkg/status (the installed packages; only those with Status
"install ok installed" count). A Packages file from apt's lists (for example
`/usr/lib/apt/apt-helper cat-file /var/lib/apt/lists/*_main_binary-amd64_Packages.lz4`) gives
the whole archive. Dependencies on packages not in the input are dropped, so every name is a
package of the input."""
import sys


def stanzas(text):
    for block in text.split("\n\n"):
        fields, key = {}, None
        for line in block.split("\n"):
            if line[:1] in (" ", "\t") and key:
                fields[key] += " " + line.strip()
            elif ":" in line:
                key, _, value = line.partition(":")
                fields[key] = value.strip()
        if "Package" in fields:
            yield fields


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "/var/lib/dpkg/status"
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read()
    except OSError as e:
        sys.exit(f"deb-deps-graph: {path}: {e.strerror}")
    packages = {}
    for s in stanzas(text):
        if "Status" in s and not s["Status"].endswith("installed"):
            continue
        if s.get("Status", "install ok installed") != "install ok installed":
            continue
        packages.setdefault(s["Package"], s)
    links = set()
    for name, s in packages.items():
        for field in ("Pre-Depends", "Depends"):
            for clause in filter(None, (c.strip() for c in s.get(field, "").split(","))):
                dep = clause.split("|")[0].split("(")[0].split("[")[0].strip().split(":")[0]
                if dep in packages and dep != name:
                    links.add((name, dep))
    if not links:
        sys.exit(f"deb-deps-graph: {path}: no dependency links among its packages")
    out = sys.stdout
    out.write("# Debian package dependencies from " + path + "\n")
    for a, b in sorted(links):
        out.write(f"{a}\t{b}\n")


if __name__ == "__main__":
    main()
