// Edit files (spec/edits.md R1-EDT-001..030): parsing, and applying a batch to a snapshot.
#include "r1/reference/edits.hpp"

#include <algorithm>
#include <unordered_map>

#include "r1/reference/intern_index.hpp"
#include "text_util.hpp"

namespace r1 {

namespace {

constexpr std::string_view kOpNames[] = {"add", "remove", "reweight"};

std::string clip(std::string_view s) { return std::string(s.substr(0, 80)); }

}  // namespace

Result<std::vector<Edit>> parse_edits(std::string_view text, const std::string& where) {
  if (auto bad = text::find_invalid_utf8(text))
    return Status::input(where + ": byte " + std::to_string(*bad) + ": edits are not valid UTF-8");
  std::vector<Edit> out;
  text::LineReader lines(text::strip_bom(text));
  std::string_view line;
  std::vector<std::string_view> f;
  while (lines.next(line)) {
    const std::string at = where + ":" + std::to_string(lines.line_number()) + ": ";
    if (text::is_blank(line) || line.front() == '#') continue;
    text::split_tabs(line, f);
    Edit e;
    e.line = lines.line_number();
    if (f[0] == "add") {
      e.op = EditOp::kAdd;
      if (f.size() < 3 || f.size() > 5)
        return Status::input(at + "add takes 2 to 4 tab-separated fields (from, to, weight, valence), found " +
                             std::to_string(f.size() - 1));
    } else if (f[0] == "remove") {
      e.op = EditOp::kRemove;
      if (f.size() != 3)
        return Status::input(at + "remove takes 2 tab-separated fields (from, to), found " + std::to_string(f.size() - 1));
    } else if (f[0] == "reweight") {
      e.op = EditOp::kReweight;
      if (f.size() != 4)
        return Status::input(at + "reweight takes 3 tab-separated fields (from, to, weight), found " +
                             std::to_string(f.size() - 1));
    } else {
      return Status::input(at + "unknown edit '" + clip(f[0]) + "' (add, remove or reweight, then TAB-separated fields)");
    }
    for (std::size_t k = 1; k <= 2; ++k) {
      if (f[k].empty()) return Status::input(at + (k == 1 ? "empty source particle" : "empty target particle"));
      if (f[k].find('\0') != std::string_view::npos) return Status::input(at + "NUL byte in a particle name");
    }
    e.from = std::string(f[1]);
    e.to = std::string(f[2]);
    if (f.size() >= 4) {
      const auto w = text::parse_weight(f[3]);
      if (!w.error.empty()) return Status::input(at + w.error);
      e.amount = w.amount;
    }
    if (f.size() == 5) {
      const auto v = text::parse_valence(f[4]);
      if (!v) return Status::input(at + "valence '" + clip(f[4]) + "' is not -1, 0 or +1");
      e.valence = *v;
    }
    out.push_back(std::move(e));
  }
  return out;
}

std::string format_edit(const Edit& e) {
  std::string o(kOpNames[static_cast<int>(e.op)]);
  o += '\t' + e.from + '\t' + e.to;
  if (e.op != EditOp::kRemove) o += '\t' + text::format_weight(e.amount);
  if (e.op == EditOp::kAdd && e.valence != 0) o += e.valence > 0 ? "\t+1" : "\t-1";
  return o;
}

Result<Snapshot> apply_edits(const Snapshot& s, const std::vector<Edit>& edits, const std::string& where,
                             EditCounts* counts) {
  EditCounts c;
  const bool named = !s.names.empty();
  // The particle table grows with added particles; indices below s.particles.size() are the
  // snapshot's own.
  std::vector<ParticleId> ids = s.particles;
  std::vector<std::string> names = s.names;
  IdIndex by_id = IdIndex::over(ids);
  NameIndex by_name = named ? NameIndex::over(names) : NameIndex();

  auto at = [&](const Edit& e) { return where + ":" + std::to_string(e.line) + ": "; };
  // The particle an edit names (R1-EDT-010): a name, else a 64-hex id; `create` allows a new one.
  auto resolve = [&](const Edit& e, const std::string& ref, bool create) -> Result<std::uint32_t> {
    if (named) {
      if (const std::int64_t k = by_name.find(ref, names); k >= 0) return static_cast<std::uint32_t>(k);
    }
    ParticleId id;
    const bool hex = hemera::from_hex(ref, id);
    if (hex) {
      if (const std::int64_t k = by_id.find(id, ids); k >= 0) return static_cast<std::uint32_t>(k);
    }
    if (!create) return Status::input(at(e) + "particle '" + clip(ref) + "' is not in the snapshot");
    if (named) {
      if (auto bad = text::find_invalid_utf8(ref)) return Status::input(at(e) + "particle name is not valid UTF-8");
      id = hemera::hash(std::string_view(ref));
      if (by_id.find(id, ids) >= 0)
        return Status::input(at(e) + "new name '" + clip(ref) + "' hashes to the id of a particle already present");
      by_name.intern(ref, names);
    } else if (!hex) {
      return Status::input(at(e) + "'" + clip(ref) + "' is not a 64-hex-digit particle id (the snapshot names particles by id)");
    }
    return by_id.intern(id, ids);
  };

  // Which links each directed pair that a remove or reweight names owns, found in one scan.
  auto key = [](std::uint32_t a, std::uint32_t b) { return (std::uint64_t{a} << 32) | b; };
  std::vector<Link> links = s.links;
  std::vector<char> dead(links.size(), 0);
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> owned;
  for (const Edit& e : edits) {
    if (e.op == EditOp::kAdd) continue;
    const std::int64_t a = named ? by_name.find(e.from, names) : -1, b = named ? by_name.find(e.to, names) : -1;
    ParticleId ia, ib;
    const std::int64_t ha = a >= 0 ? a : (hemera::from_hex(e.from, ia) ? by_id.find(ia, ids) : -1);
    const std::int64_t hb = b >= 0 ? b : (hemera::from_hex(e.to, ib) ? by_id.find(ib, ids) : -1);
    if (ha >= 0 && hb >= 0) owned.emplace(key(static_cast<std::uint32_t>(ha), static_cast<std::uint32_t>(hb)), std::vector<std::size_t>{});
  }
  if (!owned.empty())
    for (std::size_t k = 0; k < links.size(); ++k)
      if (auto it = owned.find(key(links[k].from, links[k].to)); it != owned.end()) it->second.push_back(k);

  // Fields of added links (R1-EDT-022): the all-zero neuron, the first link's token, the highest
  // height present.
  std::vector<NeuronId> neurons = s.neurons;
  std::uint32_t zero_neuron = 0;
  if (std::any_of(edits.begin(), edits.end(), [](const Edit& e) { return e.op == EditOp::kAdd; })) {
    const NeuronId zero{};
    auto it = std::find(neurons.begin(), neurons.end(), zero);
    if (it == neurons.end()) it = neurons.insert(neurons.end(), zero);
    zero_neuron = static_cast<std::uint32_t>(it - neurons.begin());
  }
  std::uint64_t height = 0;
  for (const Link& l : links) height = std::max(height, l.height);
  const std::uint32_t token = links.empty() ? s.config.tokens.begin()->first : links.front().token;

  for (const Edit& e : edits) {
    R1_ASSIGN(const std::uint32_t from, resolve(e, e.from, e.op == EditOp::kAdd));
    R1_ASSIGN(const std::uint32_t to, resolve(e, e.to, e.op == EditOp::kAdd));
    if (e.op == EditOp::kAdd) {
      Link l;
      l.amount = e.amount;
      l.height = height;
      l.neuron = zero_neuron;
      l.from = from;
      l.to = to;
      l.token = token;
      l.valence = e.valence;
      // Every pair a later edit can name is in `owned` already, or involves a particle new in
      // this batch, whose links are all added ones.
      owned[key(from, to)].push_back(links.size());
      links.push_back(l);
      dead.push_back(0);
      ++c.added;
      continue;
    }
    auto it = owned.find(key(from, to));
    std::vector<std::size_t> live;
    if (it != owned.end())
      for (std::size_t k : it->second)
        if (!dead[k]) live.push_back(k);
    if (live.empty()) return Status::input(at(e) + "no link " + clip(e.from) + " -> " + clip(e.to) + " to " +
                                           std::string(kOpNames[static_cast<int>(e.op)]));
    // remove: every link of the pair; reweight: the first keeps its place with the new amount.
    const std::size_t first = e.op == EditOp::kReweight ? 1 : 0;
    if (e.op == EditOp::kReweight) links[live[0]].amount = e.amount;
    for (std::size_t j = first; j < live.size(); ++j) dead[live[j]] = 1;
    c.links_removed += live.size() - first;
    ++(e.op == EditOp::kRemove ? c.removed : c.reweighted);
  }

  // The new snapshot: live links in order, particles renumbered by first appearance, source
  // before target (decision 2); titles and crystal tags follow by id.
  Snapshot out;
  out.source = s.source;
  out.config = s.config;
  out.card = s.card;
  constexpr std::uint32_t kNone = 0xFFFFFFFFu;
  std::vector<std::uint32_t> renumber(ids.size(), kNone), neuron_number(neurons.size(), kNone);
  std::vector<std::uint32_t> order;  // old index by new index
  auto number = [&](std::uint32_t p) {
    if (renumber[p] == kNone) {
      renumber[p] = static_cast<std::uint32_t>(order.size());
      order.push_back(p);
    }
    return renumber[p];
  };
  out.links.reserve(links.size() - c.links_removed);
  for (std::size_t k = 0; k < links.size(); ++k) {
    if (dead[k]) continue;
    Link l = links[k];
    l.from = number(l.from);
    l.to = number(l.to);
    // Neurons too are numbered by first appearance, as a reader numbers them.
    if (neuron_number[l.neuron] == kNone) {
      neuron_number[l.neuron] = static_cast<std::uint32_t>(out.neurons.size());
      out.neurons.push_back(neurons[l.neuron]);
    }
    l.neuron = neuron_number[l.neuron];
    out.links.push_back(l);
  }
  if (out.links.empty()) return Status::input(where + ": the edits leave no links");
  out.particles.reserve(order.size());
  for (std::uint32_t p : order) out.particles.push_back(ids[p]);
  if (named) {
    out.names.reserve(order.size());
    for (std::uint32_t p : order) out.names.push_back(names[p]);
  }
  if (!s.titles.empty()) {
    out.titles.assign(order.size(), {});
    for (std::size_t i = 0; i < order.size(); ++i)
      if (order[i] < s.titles.size()) out.titles[i] = s.titles[order[i]];
  }
  if (!s.crystal.empty()) {
    out.crystal.assign(order.size(), {});
    for (std::size_t i = 0; i < order.size(); ++i)
      if (order[i] < s.crystal.size()) out.crystal[i] = s.crystal[order[i]];
  }
  for (std::uint32_t p = 0; p < s.particles.size(); ++p)
    if (renumber[p] == kNone) ++c.dropped_particles;
  for (std::uint32_t p : order)
    if (p >= s.particles.size()) ++c.new_particles;
  if (counts) *counts = c;
  return out;
}

}  // namespace r1
