// Uses installed r1 headers and library: hashes "hello" and reads a tiny edge list.
#include <r1/fixedpoint/hemera.hpp>
#include <r1/reference/graph_build.hpp>
#include <r1/reference/snapshot_io.hpp>

#include <cstdio>

int main(int argc, char** argv) {
  std::printf("%s\n", r1::hemera::to_hex(r1::hemera::hash("hello")).c_str());
  if (argc > 1) {
    auto s = r1::read_snapshot(argv[1]);
    if (!s.is_ok()) {
      std::fprintf(stderr, "%s\n", s.status().message().c_str());
      return 2;
    }
    auto g = r1::build_graph(*s);
    if (!g.is_ok()) return 2;
    std::printf("%u particles\n", g->n);
  }
  return 0;
}
