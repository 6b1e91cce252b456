// r1 golden [--suite FILE] [--backend NAME] (-o DIR | --check DIR): the golden set of a suite from
// the reference backend (or the chosen one), with a report of what changed against the set already
// at DIR (spec/conformance.md R1-CONF-040..047).
#include <cstdio>
#include <iostream>

#include "backend_option.hpp"
#include "commands.hpp"
#include "progress.hpp"
#include "r1/backends/registry.hpp"
#include "r1/conformance/harness.hpp"

namespace r1::cli {

namespace {

struct GoldenOptions {
  std::string suite, out, check;
  BackendOption backend;
};

Result<conformance::Suite> load_suite(const std::string& path) {
  if (path.empty()) return conformance::default_suite();
  return conformance::read_suite(path);
}

Status run_golden(const GoldenOptions& o) {
  if (o.out.empty() == o.check.empty()) return Status::input("golden: give exactly one of -o DIR and --check DIR");
  R1_ASSIGN(const ChosenBackend chosen, o.backend.make());
  // --check compares with the set's own suite; -o writes the suite given (default: small).
  std::optional<conformance::GoldenSet> old;
  const std::string old_dir = o.check.empty() ? o.out : o.check;
  conformance::Suite suite;
  if (!o.check.empty()) {
    if (!o.suite.empty()) return Status::input("golden: --check uses the suite stored in DIR; drop --suite");
    R1_ASSIGN(conformance::GoldenSet set, conformance::read_golden(o.check));
    suite = set.suite;
    old = std::move(set);
  } else {
    R1_ASSIGN(suite, load_suite(o.suite));
    std::error_code ec;
    if (std::filesystem::exists(std::filesystem::path(o.out) / "manifest.json", ec)) {
      auto set = conformance::read_golden(o.out);
      // An earlier set of another suite is replaced without a change report.
      if (set.is_ok() && set->suite.text == suite.text) old = std::move(*set);
    }
  }
  std::printf("golden: suite %s (%zu graphs x %zu views, %dx%d) from %s\n", suite.name.c_str(), suite.graphs.size(),
              suite.views.size(), suite.width, suite.height, suite.source.c_str());
  // The reference by default; another backend writes a set of its own results, or is checked
  // against a set bit for bit (R1-CONF-047).
  backends::Backend& backend = *chosen.backend;
  if (chosen.name != "reference") std::printf("golden: backend %s (chosen by %s)\n", chosen.name.c_str(), chosen.source.c_str());
  std::vector<conformance::GraphRun> runs;
  std::size_t changed = 0;
  for (std::size_t gi = 0; gi < suite.graphs.size(); ++gi) {
    ProgressLine line;
    R1_ASSIGN(conformance::GraphRun run, conformance::run_graph(backend, suite, suite.graphs[gi], o.check.empty(), line.sink()));
    line.finish();
    std::printf("  %-14s %7zu particles  epoch %6.2f s  16 views %6.2f s  topology %.16s\n", run.name.c_str(),
                run.epoch.ids.size(), run.epoch_s, run.render_s,
                hemera::to_hex(conformance::topology_digest(run.epoch.hierarchy)).c_str());
    if (old) {
      R1_ASSIGN(const conformance::GraphComparison c, conformance::compare(run, old->graphs[gi]));
      if (!conformance::reproduces(c) || !c.positions_identical) ++changed;
      std::printf("    %s\n", conformance::describe(c).c_str());
    }
    runs.push_back(std::move(run));
  }
  if (!o.check.empty()) {
    std::printf("golden: %s: %zu of %zu graphs reproduce (topology and positions bit-identical, every view's mean dE00 <= %.1f)\n",
                o.check.c_str(), suite.graphs.size() - changed, suite.graphs.size(), conformance::kPixelBound);
    if (changed > 0) verdict_exit() = 4;
    return Status::ok();
  }
  R1_TRY(conformance::write_golden(suite, runs, o.out, chosen.name));
  if (old) {
    std::printf("golden: wrote %s (%zu of %zu graphs changed against the set it replaced)\n", o.out.c_str(), changed,
                suite.graphs.size());
  } else {
    std::printf("golden: wrote %s\n", o.out.c_str());
  }
  return Status::ok();
}

}  // namespace

void add_golden(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<GoldenOptions>();
  auto* cmd = app.add_subcommand("golden", "write (-o) or check (--check) a golden set: topology, positions and images from the reference");
  cmd->add_option("--suite", o->suite, "suite file (default: the built-in small suite, spec/suites/small.toml)");
  cmd->add_option("-o,--output", o->out, "directory to write (replaced atomically; the changes against the set there are printed)");
  cmd->add_option("--check", o->check, "compare the reference with the golden set in DIR; exit 4 when it does not reproduce");
  o->backend.add_to(*cmd);
  cmd->callback([o, &selected] { selected = [o] { return run_golden(*o); }; });
}

}  // namespace r1::cli
