// r1 conform --backend NAME [--suite FILE] [--golden DIR] [--checks LIST] -o r1_conformance.toml:
// the checks of 15 on one backend, written as the sidecar of the spec's layout
// (spec/conformance.md R1-CONF-050..064). Exit 4 when a check fails (R1-ERR-005).
#include <cstdio>
#include <iostream>
#include <sstream>

#include "backend_option.hpp"
#include "commands.hpp"
#include "image_size.hpp"
#include "r1/backends/device.hpp"
#include "r1/backends/registry.hpp"
#include "r1/conformance/conform.hpp"
#include "r1/reference/atomic_file.hpp"

namespace r1::cli {

namespace {

struct ConformCliOptions {
  BackendOption backend;
  std::string suite, golden, checks = "all", fps_epoch, tinf_epochs, tinf_sizes = "1000,10000", tinf_field = "analytic";
  std::string tinf_march = "literal", tinf_size = "480x270";
  std::uint32_t tinf_field_steps = 120;
  std::string tinf_field_block = "none";
  std::string out = "r1_conformance.toml";
  bool list = false;
};

Result<std::vector<std::int64_t>> parse_sizes(const std::string& s) {
  std::vector<std::int64_t> v;
  std::istringstream in(s);
  for (std::string w; std::getline(in, w, ',');) {
    try {
      std::size_t used = 0;
      const long long n = std::stoll(w, &used);
      // BA needs more particles than links per new node; 10^6 epochs take minutes (README).
      if (used != w.size() || n < 10 || n > 2000000) throw std::invalid_argument(w);
      v.push_back(n);
    } catch (const std::exception&) {
      return Status::input("conform: --tinf-sizes: '" + w + "' is not a particle count in 10..2000000");
    }
  }
  return v;
}

Status run_conform(const ConformCliOptions& o) {
  if (o.list) {
    for (const auto& b : backends::registered_backends())
      std::printf("%-18s %s%s\n", b.name.c_str(), b.summary.c_str(), b.expected_conformant ? "" : " [fails by design]");
    // The devices of the 13.1 trait (R1-BKD-012, R1-BKD-060): which one is here, or why not.
    std::printf("\ndevices\n%-18s %s\n", "host", backends::make_host_device()->describe().c_str());
    const auto vulkan = backends::make_vulkan_device();
    std::printf("%-18s %s\n", "vulkan", vulkan.is_ok() ? (*vulkan)->describe().c_str() : vulkan.status().message().c_str());
    return Status::ok();
  }
  R1_ASSIGN(const ChosenBackend chosen, o.backend.make());
  const std::string& name = chosen.name;
  const std::string& source = chosen.source;
  backends::Backend* backend = chosen.backend.get();
  conformance::ConformOptions co;
  R1_ASSIGN(co.checks, conformance::parse_checks(o.checks));
  R1_ASSIGN(co.tinf_sizes, parse_sizes(o.tinf_sizes));
  if (o.tinf_field != "analytic" && o.tinf_field != "neural") return Status::input("conform: --tinf-field must be analytic or neural");
  co.tinf_neural = o.tinf_field == "neural";
  if (o.tinf_march != "literal" && o.tinf_march != "skipping") return Status::input("conform: --tinf-march must be literal or skipping");
  co.tinf_literal = o.tinf_march == "literal";
  R1_ASSIGN(const auto tinf_wh, parse_image_size(o.tinf_size, "conform: --tinf-size"));
  co.tinf_width = tinf_wh.first, co.tinf_height = tinf_wh.second;
  co.tinf_field_steps = o.tinf_field_steps;
  co.tinf_field_clifford = o.tinf_field_block == "clifford";
  if (!o.tinf_epochs.empty()) {
    std::istringstream in(o.tinf_epochs);
    for (std::string w; std::getline(in, w, ',');) co.tinf_epochs.push_back(w);
  }
  co.fps_epoch = o.fps_epoch;
  if (!o.golden.empty()) {
    if (!o.suite.empty()) return Status::input("conform: --golden uses the suite stored with the golden set; drop --suite");
    R1_ASSIGN(conformance::GoldenSet g, conformance::read_golden(o.golden));
    co.suite = g.suite;
    co.golden = std::move(g);
  } else if (!o.suite.empty()) {
    R1_ASSIGN(co.suite, conformance::read_suite(o.suite));
  } else {
    R1_ASSIGN(co.suite, conformance::default_suite());
  }
  // Check that the sidecar can be written before the work (R1-ERR-003: nothing half-done).
  const std::filesystem::path out(o.out);
  const auto parent = out.has_parent_path() ? out.parent_path() : std::filesystem::path(".");
  if (!std::filesystem::is_directory(parent)) return Status::output(o.out + ": directory " + parent.string() + " does not exist");
  std::printf("conform: backend %s (chosen by %s; %s), suite %s (%zu graphs x %zu views, %dx%d), reference %s\n",
              name.c_str(), source.c_str(), std::string(backend->summary()).c_str(), co.suite.name.c_str(),
              co.suite.graphs.size(), co.suite.views.size(), co.suite.width, co.suite.height,
              co.golden ? ("golden set " + o.golden).c_str() : "computed now by the reference backend");
  std::fflush(stdout);
  R1_ASSIGN(const conformance::ConformReport rep, conformance::conform(*backend, co, [](const std::string& line) {
              std::printf("  %s\n", line.c_str());
              std::fflush(stdout);
            }));
  const auto& calls = backend->calls();
  std::printf("conform: %s ran %llu epoch stage calls and %llu frames\n", name.c_str(),
              static_cast<unsigned long long>(calls.total() - calls[Stage::kRender]), static_cast<unsigned long long>(calls[Stage::kRender]));
  const std::string toml = conformance::sidecar_toml(rep);
  R1_TRY(write_file_atomic(out, toml));
  std::printf("%s", toml.c_str());
  std::size_t failed = 0;
  for (const auto& r : rep.results) failed += r.passed ? 0 : 1;
  std::printf("conform: %s: %zu of %zu checks pass; wrote %s\n", failed ? "FAIL" : "PASS", rep.results.size() - failed,
              rep.results.size(), o.out.c_str());
  if (failed) verdict_exit() = 4;
  return Status::ok();
}

}  // namespace

void add_conform(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<ConformCliOptions>();
  auto* cmd = app.add_subcommand("conform", "run the R-1.0 section 15 checks on a backend and write r1_conformance.toml");
  o->backend.add_to(*cmd);
  cmd->add_option("--suite", o->suite, "suite file (default: the built-in small suite)");
  cmd->add_option("--golden", o->golden, "compare with this golden set (from r1 golden) instead of running the reference");
  cmd->add_option("--checks", o->checks, "checks to run: all, or a list of topo,pos,pix,fps,tinf (default all)");
  cmd->add_option("--fps-epoch", o->fps_epoch, "epoch directory of a 10^6-particle snapshot for P_RENDER_FPS");
  cmd->add_option("--tinf-epochs", o->tinf_epochs, "extra epoch directories (comma-separated) for P_RENDER_TINF");
  cmd->add_option("--tinf-sizes", o->tinf_sizes, "BA graph sizes generated for P_RENDER_TINF (default 1000,10000)");
  cmd->add_option("--tinf-field-steps", o->tinf_field_steps, "with --tinf-field neural: Adam steps of each training (120)")
      ->check(CLI::Range(1u, 1000000u));
  cmd->add_option("--tinf-field-block", o->tinf_field_block, "with --tinf-field neural: the network, none (default) or clifford")
      ->check(CLI::IsMember({"none", "clifford"}));
  cmd->add_option("--tinf-march", o->tinf_march,
                  "with --tinf-field neural: literal (every pixel's 128 samples, R1-NRF-033; default) or skipping (the samples some node reaches)");
  cmd->add_option("--tinf-size", o->tinf_size, "P_RENDER_TINF's frame WIDTHxHEIGHT (480x270)");
  cmd->add_option("--tinf-field", o->tinf_field, "P_RENDER_TINF's far field: analytic (the backend's frames, default) or neural (trained per epoch, reference renderer)");
  cmd->add_option("-o,--output", o->out, "sidecar to write (default r1_conformance.toml)");
  cmd->add_flag("--list", o->list, "list the built backends and exit");
  cmd->callback([o, &selected] { selected = [o] { return run_conform(*o); }; });
}

}  // namespace r1::cli
