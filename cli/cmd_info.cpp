// r1 info FILE [--json]: counts, components, degrees and the snapshot digest (R1-IN-060).
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "input_options.hpp"
#include "progress.hpp"
#include "timing.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/snapshot_io.hpp"
#include "r1/reference/summary.hpp"

namespace r1::cli {

namespace {

struct InfoOptions {
  std::string file;
  InputOptions input;
  bool json = false;
  bool no_digest = false;
  bool timings = false;
};

nlohmann::json stats_json(const DegreeStats& d) {
  return {{"min", d.min}, {"max", d.max}, {"mean", d.mean}, {"median", d.median}};
}

Status run_info(const InfoOptions& o) {
  ProgressLine progress;
  R1_ASSIGN(const ReadOptions ro, o.input.read_options(progress.sink()));

  const auto t0 = std::chrono::steady_clock::now();
  R1_ASSIGN(Snapshot s, read_snapshot(o.file, ro));
  const double load_s = seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  R1_ASSIGN(Graph g, build_graph(s, progress.sink()));
  const double graph_s = seconds_since(t1);
  SnapshotSummary sum = summarize(s, g);
  double digest_s = 0;
  if (!o.no_digest) {
    const auto t2 = std::chrono::steady_clock::now();
    report(ro.progress, "hashing records", 0, 0);
    sum.digest = hemera::to_hex(snapshot_digest(s));
    digest_s = seconds_since(t2);
  }
  progress.finish();

  if (o.json) {
    nlohmann::json j = {{"file", o.file},
                        {"chain_id", sum.chain_id},
                        {"block", sum.block},
                        {"particles", sum.particles},
                        {"links", sum.links},
                        {"neurons", sum.neurons},
                        {"self_loops_dropped", sum.self_loops_dropped},
                        {"pairs", sum.pairs},
                        {"components", sum.components},
                        {"largest_component", sum.largest_component},
                        {"isolated", sum.isolated},
                        {"anchor", sum.anchor},
                        {"titles", sum.titles},
                        {"crystal", sum.crystal},
                        {"degree", stats_json(sum.degree)},
                        {"weighted_degree", stats_json(sum.weighted_degree)},
                        {"digest", sum.digest ? nlohmann::json(*sum.digest) : nlohmann::json(nullptr)}};
    if (o.timings)
      j["timing"] = {{"load_s", load_s}, {"graph_s", graph_s}, {"digest_s", digest_s}, {"peak_rss_mib", peak_rss_mib()}};
    std::cout << j.dump(2) << "\n";
    return Status::ok();
  }
  std::printf("file               %s\n", o.file.c_str());
  std::printf("chain              %s, block %llu\n", sum.chain_id.c_str(), static_cast<unsigned long long>(sum.block));
  std::printf("particles          %llu (anchor: first %llu)\n", static_cast<unsigned long long>(sum.particles),
              static_cast<unsigned long long>(sum.anchor));
  std::printf("links              %llu (%llu self-loops dropped, %llu linked pairs)\n",
              static_cast<unsigned long long>(sum.links), static_cast<unsigned long long>(sum.self_loops_dropped),
              static_cast<unsigned long long>(sum.pairs));
  std::printf("neurons            %llu\n", static_cast<unsigned long long>(sum.neurons));
  std::printf("components         %llu (largest %llu particles, %llu isolated)\n",
              static_cast<unsigned long long>(sum.components), static_cast<unsigned long long>(sum.largest_component),
              static_cast<unsigned long long>(sum.isolated));
  std::printf("degree             min %.0f  median %.1f  mean %.2f  max %.0f\n", sum.degree.min, sum.degree.median,
              sum.degree.mean, sum.degree.max);
  std::printf("weighted degree    min %.4g  median %.4g  mean %.4g  max %.4g\n", sum.weighted_degree.min,
              sum.weighted_degree.median, sum.weighted_degree.mean, sum.weighted_degree.max);
  if (sum.titles > 0) std::printf("titles             %llu\n", static_cast<unsigned long long>(sum.titles));
  if (sum.crystal > 0) std::printf("crystal metadata   %llu particles\n", static_cast<unsigned long long>(sum.crystal));
  std::printf("digest             %s\n", sum.digest ? sum.digest->c_str() : "(not computed: --no-digest)");
  if (o.timings)
    std::printf("timing             load %.2f s, graph %.2f s, digest %.2f s; peak memory %.0f MiB\n", load_s, graph_s,
                digest_s, peak_rss_mib());
  return Status::ok();
}

}  // namespace

void add_info(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<InfoOptions>();
  auto* cmd = app.add_subcommand("info", "summarise a snapshot: counts, components, degrees, digest");
  cmd->add_option("FILE", o->file, "snapshot: .graph, TSV/CSV edge list or Matrix Market (- for stdin)")->required();
  o->input.add_to(*cmd);
  cmd->add_flag("--json", o->json, "print one JSON object");
  cmd->add_flag("--no-digest", o->no_digest, "skip the snapshot digest (Hemera over every record; slow on huge inputs)");
  cmd->add_flag("--timings", o->timings, "also report load/graph/digest times and peak memory");
  cmd->callback([o, &selected] { selected = [o] { return run_info(*o); }; });
}

}  // namespace r1::cli
