#!/usr/bin/env bash
# Installs the build tree BUILD_DIR into a scratch prefix, then configures, builds and runs the
# consumer project in tests/install_consumer against it (find_package(r1 CONFIG), r1::r1).
set -euo pipefail
build=$1
root=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" >/dev/null
test -x "$work/prefix/bin/r1"
test -f "$work/prefix/include/r1/fixedpoint/hemera.hpp"
cmake -S "$root/tests/install_consumer" -B "$work/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/consumer" >/dev/null
out=$("$work/consumer/consumer" "$root/tests/good_input/crlf_bom_header.tsv")
expected=$'e1b19b8235443e9fac8f1d6a1203de66e9a58c53e36cbbc1f71a031c3d13ce77\n3 particles'
if [ "$out" != "$expected" ]; then echo "consumer printed: $out" >&2; exit 1; fi
out=$("$work/consumer/backend_consumer")
expected=$'cpu 5/5\nnull 0/5'
if [ "$out" != "$expected" ]; then echo "backend_consumer printed: $out" >&2; exit 1; fi
"$work/prefix/bin/r1" hash --tree - </dev/null >/dev/null
echo "install test passed"
