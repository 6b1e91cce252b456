// r1 spectrum FILE [--backend NAME]: the spectral embedding alone, for inspection, timing and the
// eigsh peer comparison (R1-SPEC-060..064, R1-SPEC-070..071, R1-BKD-016).
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "backend_option.hpp"
#include "commands.hpp"
#include "input_options.hpp"
#include "progress.hpp"
#include "timing.hpp"
#include "r1/format/bytes.hpp"
#include "r1/reference/atomic_file.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/graph_park.hpp"
#include "r1/reference/snapshot_io.hpp"
#include "r1/reference/operator_export.hpp"
#include "r1/solvers/spectral.hpp"

namespace r1::cli {

namespace {

struct SpectrumOptions {
  std::string file;
  InputOptions input;
  BackendOption backend;
  std::string domain = "q32";
  std::optional<double> rho;
  double tolerance = SpectralParams{}.tolerance;
  std::uint32_t basis = SpectralParams{}.basis;
  std::uint32_t max_restarts = 0;
  std::uint32_t filter_degree = SpectralParams{}.filter_degree;
  bool parallel = false;
  bool json = false;
  std::string vectors, laplacian;
};

double as_double(fx::Q32 v) { return v.to_double(); }
double as_double(double v) { return v; }

// u_2..u_6 as little-endian doubles, n rows of 5, row-major (Q32 entries convert exactly).
template <class Scalar>
Status write_vectors(const Spectrum<Scalar>& s, const std::string& path) {
  AtomicFile f(path);
  R1_TRY(f.open());
  std::string buf;
  buf.reserve(1u << 20);
  for (std::uint32_t i = 0; i < s.n; ++i) {
    for (std::size_t c = 0; c < 5; ++c) {
      format::put_f64(buf, as_double(s.u[c][i]));
    }
    if (buf.size() >= (1u << 20)) {
      R1_TRY(f.write(buf));
      buf.clear();
    }
  }
  R1_TRY(f.write(buf));
  return f.commit();
}

template <class Scalar>
Status report_spectrum(const SpectrumOptions& o, const Graph& g, const Spectrum<Scalar>& s, double load_s,
                       double solve_s) {
  if (!o.vectors.empty()) R1_TRY(write_vectors(s, o.vectors));
  if (o.json) {
    nlohmann::json j = {{"file", o.file},
                        {"domain", o.domain},
                        {"n", s.n},
                        {"nnz", g.nnz()},
                        {"rho", s.rho},
                        {"eigenvalues", s.eigenvalues},
                        {"residuals", s.residuals},
                        {"found", s.found},
                        {"restarts", s.restarts},
                        {"matvecs", s.matvecs},
                        {"block_applications", s.passes},
                        {"tolerance", o.tolerance},
                        {"filter_degree", o.filter_degree},
                        {"load_s", load_s},
                        {"solve_s", solve_s},
                        {"peak_rss_mib", peak_rss_mib()}};
    std::cout << j.dump(2) << "\n";
    return Status::ok();
  }
  std::printf("particles    %u (%llu stored entries), domain %s, rho %.17g\n", s.n,
              static_cast<unsigned long long>(g.nnz()), o.domain.c_str(), s.rho);
  for (std::size_t k = 0; k < 6; ++k)
    std::printf("lambda_%zu     %.17g  residual %.3g%s\n", k + 1, s.eigenvalues[k], s.residuals[k],
                k > s.found ? "  (missing: n < 7)" : "");
  std::printf("work         %u restarts, %u block applications of L (%u vectors)\n", s.restarts, s.passes, s.matvecs);
  std::printf("time         load %.3f s, solve %.3f s; peak memory %.0f MiB\n", load_s, solve_s, peak_rss_mib());
  return Status::ok();
}

Status run_spectrum(const SpectrumOptions& o) {
  if (o.domain != "q32" && o.domain != "fp64")
    return Status::input("--domain '" + o.domain + "' is not one of q32, fp64");
  R1_ASSIGN(const ChosenBackend chosen, o.backend.make());
  // The stage interface returns Q32 (R1-BKD-010), so fp64's unrounded vectors come only from the
  // reference's fp64 solver: --domain fp64 is that solver, for the backends whose stage it is.
  if (o.domain == "fp64" && chosen.name != "reference" && chosen.name != "fp64")
    return Status::input("spectrum: --domain fp64 reports the reference's fp64 solver unrounded; backend '" + chosen.name +
                         "' returns its spectrum in Q32: drop --domain fp64 or use --backend reference");
  ProgressLine progress;
  R1_ASSIGN(const ReadOptions ro, o.input.read_options(progress.sink()));
  const auto t0 = std::chrono::steady_clock::now();
  // Only the layout graph is needed from here on: its build lets the link records go as it fills
  // its rows, and the snapshot goes once it is built (R1-SPEC-077).
  Graph g;
  {
    R1_ASSIGN(Snapshot snap, read_snapshot(o.file, ro));
    R1_ASSIGN(g, build_graph_releasing_links(snap, progress.sink()));
  }
  const double load_s = seconds_since(t0);
  SpectralParams p;
  p.rho = o.rho;
  p.tolerance = o.tolerance;
  p.basis = o.basis;
  p.max_restarts = o.max_restarts;
  p.filter_degree = o.filter_degree;
  SpectralOptions so;
  so.parallel = o.parallel;
  // Once the solver has formed its operator, the graph's other arrays are not read again
  // (R1-EPO-006): they go, and the solve's peak is the epoch's.
  so.operator_ready = [&g] { release_unread_by_spectral(g); };
  if (!o.laplacian.empty()) {
    if (o.domain == "q32") {
      R1_ASSIGN(const auto op, spectral_operator_q32(g, p));
      R1_TRY(write_operator_matrix_market(op, o.laplacian));
    } else {
      R1_ASSIGN(const auto op, spectral_operator_f64(g, p));
      R1_TRY(write_operator_matrix_market(op, o.laplacian));
    }
  }
  const auto t1 = std::chrono::steady_clock::now();
  if (o.domain == "q32") {
    // The chosen backend's spectral stage (R1-BKD-016): the reference's is spectral_embedding_q32.
    EpochOptions eo;
    eo.spectral = p;
    eo.parallel = o.parallel;
    eo.spectral_operator_ready = so.operator_ready;
    R1_ASSIGN(const auto s, chosen.backend->spectral(g, eo, progress.sink()));
    const double solve_s = seconds_since(t1);
    progress.finish();
    return report_spectrum(o, g, s, load_s, solve_s);
  }
  R1_ASSIGN(const auto s, spectral_embedding_f64(g, p, progress.sink(), so));
  const double solve_s = seconds_since(t1);
  progress.finish();
  return report_spectrum(o, g, s, load_s, solve_s);
}

}  // namespace

void add_spectrum(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<SpectrumOptions>();
  auto* cmd = app.add_subcommand("spectrum", "the spectral embedding alone: lambda_1..6, residuals, u_2..u_6");
  cmd->add_option("FILE", o->file, "snapshot: .graph, TSV/CSV edge list or Matrix Market (- for stdin)")->required();
  o->input.add_to(*cmd);
  o->backend.add_to(*cmd);
  cmd->add_option("--domain", o->domain, "q32 (canonical, default) or fp64");
  cmd->add_option("--rho", o->rho, "regularisation rho >= 0 (default: 0 if connected, else the mean weighted degree)");
  cmd->add_option("--tolerance", o->tolerance, "residual target ||L u - lambda u|| (default 1e-9)");
  cmd->add_option("--basis", o->basis, "block Krylov steps per restart cycle (7 vectors each), 4..200 (default 14)");
  cmd->add_option("--filter-degree", o->filter_degree, "Chebyshev filter degree after the first cycle, 0..64 (default 12; 0: none)");
  cmd->add_option("--max-restarts", o->max_restarts, "restart cap (default 0: the solver's own, 1000)");
  cmd->add_flag("--parallel", o->parallel, "TBB kernels (bit-identical to the serial default)");
  cmd->add_flag("--json", o->json, "print one JSON object");
  cmd->add_option("--vectors", o->vectors, "write u_2..u_6 as little-endian f64, n rows of 5");
  cmd->add_option("--laplacian", o->laplacian,
                  "write the operator iterated on as Matrix Market real symmetric (rank-one part on %r1-rank-one lines)");
  cmd->callback([o, &selected] { selected = [o] { return run_spectrum(*o); }; });
}

}  // namespace r1::cli
