// r1 gen KIND [options] -o FILE: writes a generated snapshot (R1-GEN-001..004).
#include <charconv>
#include <iostream>

#include "commands.hpp"
#include "progress.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/snapshot_io.hpp"

namespace r1::cli {

namespace {
struct GenOptions {
  std::string kind;
  std::string output;
  std::string seed = "1";  // parsed here: CLI11 would wrap "-1" into an unsigned value
  std::int64_t n = 0, m = 0, k = 0;
  std::vector<std::int64_t> sizes;
  std::string dims;
  double p_in = 0, p_out = 0, p_triad = 0, radius = 0;
  // Which options were given: unset ones take the kind's default, stray ones are errors.
  CLI::Option *n_opt = nullptr, *m_opt = nullptr, *k_opt = nullptr, *dims_opt = nullptr;
  CLI::Option *p_in_opt = nullptr, *p_out_opt = nullptr, *p_triad_opt = nullptr, *radius_opt = nullptr;
};

template <class T>
std::optional<T> given(const CLI::Option* opt, T value) {
  return opt->count() > 0 ? std::optional<T>(value) : std::nullopt;
}

Result<GenParams> to_params(const GenOptions& o) {
  R1_ASSIGN(const GenKind kind, gen_kind_from_name(o.kind));
  GenParams p;
  p.kind = kind;
  std::uint64_t seed = 0;
  const auto r = std::from_chars(o.seed.data(), o.seed.data() + o.seed.size(), seed);
  if (o.seed.empty() || r.ec != std::errc() || r.ptr != o.seed.data() + o.seed.size())
    return Status::input("gen: --seed must be an integer from 0 to 2^64 - 1 (got '" + o.seed + "')");
  p.seed = seed;
  p.n = given(o.n_opt, o.n);
  p.m = given(o.m_opt, o.m);
  p.k = given(o.k_opt, o.k);
  p.sizes = o.sizes;
  if (o.dims_opt->count() > 0) {
    R1_ASSIGN(p.dims, parse_dims(o.dims));
  }
  p.p_in = given(o.p_in_opt, o.p_in);
  p.p_out = given(o.p_out_opt, o.p_out);
  p.p_triad = given(o.p_triad_opt, o.p_triad);
  p.radius = given(o.radius_opt, o.radius);
  return p;
}

Status run_gen(const GenOptions& o) {
  R1_ASSIGN(const GenParams p, to_params(o));
  ProgressLine line;
  R1_ASSIGN(const Snapshot s, generate(p, line.sink()));
  const Status written = write_snapshot(s, o.output);
  line.finish();
  R1_TRY(written);
  std::cout << o.output << ": " << s.particles.size() << " particles, " << s.links.size() << " links\n";
  return Status::ok();
}
}  // namespace

void add_gen(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<GenOptions>();
  auto* cmd = app.add_subcommand("gen", "write a generated graph snapshot (.graph, .tsv or .csv by FILE's extension)");
  cmd->add_option("KIND", o->kind, "ring, path, star, grid, torus, complete, sbm, ba, rgg or crystal")->required();
  cmd->add_option("-o,--output", o->output, "output FILE; .tsv and .csv write edge lists, anything else .graph")
      ->required();
  cmd->add_option("--seed", o->seed, "seed of the counter-based RNG, 0..2^64-1 (default 1)");
  o->n_opt = cmd->add_option("--n", o->n, "nodes");
  o->m_opt = cmd->add_option("--m", o->m, "ba: links per new node");
  o->k_opt = cmd->add_option("--k", o->k, "sbm: number of blocks of equal size");
  cmd->add_option("--sizes", o->sizes, "sbm: block sizes, comma-separated")->delimiter(',');
  o->dims_opt = cmd->add_option("--dims", o->dims, "grid: WxH; torus: AxBxC");
  o->p_in_opt = cmd->add_option("--p-in", o->p_in, "sbm: link probability inside a block; crystal: inside a domain");
  o->p_out_opt = cmd->add_option("--p-out", o->p_out, "sbm: across blocks; crystal: across triads");
  o->p_triad_opt = cmd->add_option("--p-triad", o->p_triad, "crystal: between domains of one triad");
  o->radius_opt = cmd->add_option("--radius", o->radius, "rgg: link radius in the unit cube");
  cmd->footer(gen_help_text());
  cmd->callback([o, &selected] { selected = [o] { return run_gen(*o); }; });
}

}  // namespace r1::cli
