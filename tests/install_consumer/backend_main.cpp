// Uses the installed backend registry and property library: runs the properties on `cpu`
// and on `null`, and prints how many each passes.
#include <r1/backends/registry.hpp>
#include <r1/conformance/properties.hpp>

#include <cstdio>

int main() {
  r1::conformance::PropertyOptions o;
  o.tests = 3;
  o.pixels = false;
  for (const char* name : {"cpu", "null"}) {
    auto b = r1::backends::make_backend(name);
    if (!b.is_ok()) return 2;
    int passed = 0, total = 0;
    for (const auto& r : r1::conformance::check_backend(**b, o)) {
      ++total;
      passed += r.passed ? 1 : 0;
    }
    std::printf("%s %d/%d\n", name, passed, total);
  }
  return 0;
}
