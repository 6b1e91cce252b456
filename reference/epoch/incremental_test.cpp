// Incremental epochs (spec/incremental.md R1-INC-001..040): the edit batch against a dense
// oracle of ||Delta L~||_2, N_h, h, the certificate against the exact eigenvectors of a dense
// solve (Eigen), frozen positions outside N_h, the fall-back and its reasons.
#include "r1/reference/incremental.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <rapidcheck.h>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <functional>
#include <set>

#include "r1/format/hierarchy.hpp"
#include "r1/reference/edits.hpp"
#include "r1/reference/encoding.hpp"
#include "r1/reference/epoch.hpp"
#include "r1/reference/epoch_io.hpp"
#include "r1/reference/frame.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/hierarchy.hpp"
#include "r1/solvers/focus.hpp"
#include "r1/solvers/spectral.hpp"
#include "rc_cases.hpp"

namespace {

r1::Snapshot rgg(std::int64_t n, std::uint64_t seed = 1, std::optional<double> radius = {}) {
  r1::GenParams p;
  p.kind = r1::GenKind::kRgg;
  p.n = n;
  p.seed = seed;
  p.radius = radius;
  auto s = r1::generate(p);
  EXPECT_TRUE(s.is_ok()) << s.status().message();
  return std::move(*s);
}

r1::Snapshot edited(const r1::Snapshot& s, const std::string& edits) {
  auto e = r1::parse_edits(edits, "batch");
  EXPECT_TRUE(e.is_ok()) << e.status().message();
  auto r = r1::apply_edits(s, *e, "batch");
  EXPECT_TRUE(r.is_ok()) << r.status().message();
  return std::move(*r);
}

r1::Graph graph(const r1::Snapshot& s) {
  auto g = r1::build_graph(s);
  EXPECT_TRUE(g.is_ok()) << g.status().message();
  return std::move(*g);
}

r1::Epoch full_epoch(const r1::Snapshot& s) {
  const r1::Graph g = graph(s);
  auto e = r1::run_epoch(s, g, r1::EpochOptions{});
  EXPECT_TRUE(e.is_ok()) << e.status().message();
  return std::move(*e);
}

// The operator the solver iterates on, dense, from its exact Q32 entries (raws are exact doubles).
Eigen::MatrixXd dense_operator(const r1::Graph& g) {
  auto op = r1::spectral_operator_q32(g, r1::SpectralParams{});
  EXPECT_TRUE(op.is_ok());
  Eigen::MatrixXd l = Eigen::MatrixXd::Identity(g.n, g.n);
  for (std::uint32_t i = 0; i < g.n; ++i)
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k)
      l(i, g.col[k]) -= static_cast<double>(op->m[k].raw) * 0x1p-32;
  return l;
}

// The exact normalised-adjacency entries w / sqrt(d_i d_j) of a graph, dense.
Eigen::MatrixXd dense_m(const r1::Graph& g) {
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(g.n, g.n);
  for (std::uint32_t i = 0; i < g.n; ++i)
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k)
      m(i, g.col[k]) = static_cast<double>(g.w[k]) /
                       std::sqrt(static_cast<double>(g.degree[i]) * static_cast<double>(g.degree[g.col[k]]));
  return m;
}

TEST(Incremental, HopsMeetTheYukawaTailAndAreTheLeastThatDo) {
  EXPECT_EQ(r1::hops_for(1e-3, 1.0), 9u);
  for (double mu : {0.25, 0.5, 1.0, 2.0, 7.5})
    for (double eps : {0.3, 1e-2, 1e-3, 1e-6}) {
      const std::uint32_t h = r1::hops_for(eps, mu);
      ASSERT_GE(h, 1u);
      if (h == 64) continue;  // the cap
      EXPECT_GE(mu * std::pow(1 + mu, h + 1) * eps, 1.0 - 1e-12) << mu << " " << eps;
      if (h > 1) {
        EXPECT_LT(mu * std::pow(1 + mu, h) * eps, 1.0 + 1e-12) << mu << " " << eps;
      }
    }
}

TEST(Incremental, NeighbourhoodIsTheBallOfHHops) {
  r1::GenParams p;
  p.kind = r1::GenKind::kPath;
  p.n = 20;
  const r1::Graph g = graph(*r1::generate(p));
  EXPECT_EQ(r1::neighbourhood(g, {5}, 2), (std::vector<std::uint32_t>{3, 4, 5, 6, 7}));
  EXPECT_EQ(r1::neighbourhood(g, {0, 19}, 1), (std::vector<std::uint32_t>{0, 1, 18, 19}));
  EXPECT_EQ(r1::neighbourhood(g, {}, 3), std::vector<std::uint32_t>{});
  // On a scale-free graph, against a plain breadth-first search with a mark per particle: small
  // balls (sorted sets only) and balls that pass n / 16 (the marks take over), seeds repeated.
  r1::GenParams ba;
  ba.kind = r1::GenKind::kBa;
  ba.n = 2000;
  ba.seed = 3;
  const r1::Graph b = graph(*r1::generate(ba));
  for (const std::vector<std::uint32_t>& seeds : {std::vector<std::uint32_t>{1999}, std::vector<std::uint32_t>{1500, 1700, 1500},
                                                  std::vector<std::uint32_t>{0, 5, 900, 1999}})
    for (std::uint32_t h = 0; h <= 4; ++h) {
      std::vector<char> in(b.n, 0);
      std::vector<std::uint32_t> frontier;
      for (const std::uint32_t x : seeds)
        if (!in[x]) {
          in[x] = 1;
          frontier.push_back(x);
        }
      for (std::uint32_t k = 0; k < h; ++k) {
        std::vector<std::uint32_t> next;
        for (const std::uint32_t i : frontier)
          for (std::uint64_t e = b.row_ptr[i]; e < b.row_ptr[i + 1]; ++e)
            if (!in[b.col[e]]) {
              in[b.col[e]] = 1;
              next.push_back(b.col[e]);
            }
        frontier = next;
      }
      std::vector<std::uint32_t> want;
      for (std::uint32_t i = 0; i < b.n; ++i)
        if (in[i]) want.push_back(i);
      EXPECT_EQ(r1::neighbourhood(b, seeds, h), want) << "h " << h << ", " << seeds.size() << " seeds";
    }
}

// A link that only changes direction leaves A_sym and A2 alone but not the focus's A0: both
// endpoints are touched (by their out-row digests), the operator bound stays at rounding level,
// and the focus update runs on them.
TEST(Incremental, ADirectionChangeTouchesBothEndpoints) {
  const r1::Snapshot s = rgg(300);
  const r1::Epoch prev = full_epoch(s);
  const std::string a = s.names[s.links[0].from], b = s.names[s.links[0].to];
  const r1::Snapshot next = edited(s, "remove\t" + a + "\t" + b + "\nadd\t" + b + "\t" + a + "\n");
  const r1::Graph g = graph(next);
  auto batch = r1::edit_batch(prev, next, g, "prev");
  ASSERT_TRUE(batch.is_ok()) << batch.status().message();
  // Particles are renumbered by first appearance; find the two endpoints by name.
  std::vector<std::uint32_t> want;
  for (std::uint32_t i = 0; i < g.n; ++i)
    if (next.names[i] == a || next.names[i] == b) want.push_back(i);
  ASSERT_EQ(want.size(), 2u);
  EXPECT_TRUE(batch->touched == want) << batch->touched.size() << " touched";
  EXPECT_EQ(batch->added + batch->dropped, 0u);
  EXPECT_LT(batch->delta_norm, 1e-9);  // A_sym and A2 as they were: rounding allowance only
}

TEST(Incremental, TouchedRowsAndTheNormBoundAgainstADenseOracle) {
  const r1::Snapshot s = rgg(300);
  const r1::Epoch prev = full_epoch(s);
  const std::string a = s.names[s.links[0].from], b = s.names[s.links[0].to];
  const std::string c = s.names[s.links[7].from], d = s.names[s.links[7].to];
  // Adds between far-apart particles (rows early and late in the order), and a new particle.
  std::string adds;
  for (std::size_t k = 0; k < 6; ++k)
    adds += "add\t" + s.names[(37 * k + 5) % s.names.size()] + "\t" + s.names[(101 * k + 290) % s.names.size()] + "\t0.75\n";
  for (const std::string& batch :
       {"reweight\t" + a + "\t" + b + "\t0.5\n", "reweight\t" + c + "\t" + d + "\t0.125\nadd\t" + a + "\t" + d + "\t0.25\n", adds,
        adds + "add\t" + c + "\tnewcomer\t2\n"}) {
    const r1::Snapshot next = edited(s, batch);
    const r1::Graph g = graph(next);
    auto batch_r = r1::edit_batch(prev, next, g, "prev");
    ASSERT_TRUE(batch_r.is_ok()) << batch_r.status().message();
    // Touched: exactly the rows that differ (the same particle order here: no particle moved;
    // a new one comes last and is touched).
    ASSERT_TRUE(std::equal(s.particles.begin(), s.particles.end(), next.particles.begin()));
    const r1::Graph g0 = graph(s);
    std::vector<std::uint32_t> want;
    for (std::uint32_t i = 0; i < g.n; ++i) {
      if (i >= g0.n) {
        want.push_back(i);
        continue;
      }
      const bool same = g.row_ptr[i + 1] - g.row_ptr[i] == g0.row_ptr[i + 1] - g0.row_ptr[i] &&
                        std::equal(g.col.begin() + static_cast<std::ptrdiff_t>(g.row_ptr[i]),
                                   g.col.begin() + static_cast<std::ptrdiff_t>(g.row_ptr[i + 1]),
                                   g0.col.begin() + static_cast<std::ptrdiff_t>(g0.row_ptr[i])) &&
                        std::equal(g.w.begin() + static_cast<std::ptrdiff_t>(g.row_ptr[i]),
                                   g.w.begin() + static_cast<std::ptrdiff_t>(g.row_ptr[i + 1]),
                                   g0.w.begin() + static_cast<std::ptrdiff_t>(g0.row_ptr[i]));
      if (!same) want.push_back(i);
    }
    EXPECT_EQ(batch_r->touched, want);
    EXPECT_EQ(batch_r->added, g.n - g0.n);
    if (g.n != g0.n) continue;  // the dense comparison below needs one size
    // The bound holds for the operators' true difference (rounded entries included) and for the
    // exact entries, and is not looser than the Frobenius norm plus the rounding allowance.
    const Eigen::MatrixXd dl = dense_operator(g) - dense_operator(g0);
    const Eigen::MatrixXd dm = dense_m(g) - dense_m(g0);
    auto norm2 = [](const Eigen::MatrixXd& x) {
      return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(x).eigenvalues().cwiseAbs().maxCoeff();
    };
    EXPECT_GE(batch_r->delta_norm, norm2(dl));
    EXPECT_GE(batch_r->delta_norm, norm2(dm));
    EXPECT_LE(batch_r->delta_norm, dm.norm() + 1e-6);
  }
}

TEST(Incremental, AddedDroppedAndAnotherChain) {
  const r1::Snapshot s = rgg(1500);
  const r1::Epoch prev = full_epoch(s);
  // A new particle, and one that loses every link (the last in canonical order: not an anchor).
  std::string batch = "add\t" + s.names[3] + "\tnewcomer\n";
  const std::string lone = s.names.back();
  for (const r1::Link& l : s.links)
    if (s.names[l.from] == lone || s.names[l.to] == lone) batch += "remove\t" + s.names[l.from] + "\t" + s.names[l.to] + "\n";
  const r1::Snapshot next = edited(s, batch);
  auto b = r1::edit_batch(prev, next, graph(next), "prev");
  ASSERT_TRUE(b.is_ok()) << b.status().message();
  EXPECT_EQ(b->added, 1u);
  EXPECT_EQ(b->dropped, 1u);
  EXPECT_EQ(b->prev_of[next.particles.size() - 1], -1);

  r1::GenParams p;
  p.kind = r1::GenKind::kRing;
  p.n = 50;
  const r1::Snapshot other = *r1::generate(p);
  auto bad = r1::edit_batch(prev, other, graph(other), "prev");
  ASSERT_FALSE(bad.is_ok());
  EXPECT_NE(bad.status().message().find("prev: not an epoch of this snapshot's chain: its anchor particle 0"), std::string::npos)
      << bad.status().message();
}

struct UpdateRun {
  r1::Snapshot s, next;
  r1::Epoch prev, epoch;
  r1::Graph g;
};

// PREV = the full epoch of an rgg graph; NEXT = it with the batch `make(s)`, from PREV.
UpdateRun incremental_run(const std::function<std::string(const r1::Snapshot&)>& make, const r1::UpdateOptions& uo) {
  UpdateRun r;
  r.s = rgg(1000, 3);
  r.prev = full_epoch(r.s);
  r.next = edited(r.s, make(r.s));
  r.g = graph(r.next);
  const r1::Anchor anchor = r1::make_anchor(r.s, r.prev.frame);
  r1::ReferenceStages stages;
  auto e = r1::run_epoch_from(r.prev, anchor, "prev", r.next, r.g, r1::EpochOptions{}, uo, stages);
  EXPECT_TRUE(e.is_ok()) << e.status().message();
  if (e.is_ok()) r.epoch = std::move(*e);
  return r;
}

// A reweight of one link (below the largest weight, so no other row rescales).
std::string reweight(const r1::Snapshot& s, const char* w) {
  return "reweight\t" + s.names[s.links[10].from] + "\t" + s.names[s.links[10].to] + "\t" + w + "\n";
}
std::string small_reweight(const r1::Snapshot& s) { return reweight(s, "0.999"); }

// NEXT = PREV's own snapshot: nothing is touched, the epoch is incremental and every particle
// keeps its vectors, position and focus bit for bit (the focus update of an empty region is the
// start, R1-INC-051).
TEST(Incremental, AnEmptyBatchKeepsEverything) {
  r1::UpdateOptions uo;
  uo.hops = 2;
  const UpdateRun r = incremental_run([](const r1::Snapshot&) { return std::string(); }, uo);
  ASSERT_TRUE(r.epoch.update.has_value());
  const r1::UpdateInfo& u = *r.epoch.update;
  EXPECT_TRUE(u.incremental) << u.reason;
  EXPECT_EQ(u.touched, 0u);
  EXPECT_EQ(u.region, 0u);
  EXPECT_TRUE(u.focus_local);
  EXPECT_EQ(r.epoch.focus.phi, r.prev.focus.phi);
  EXPECT_EQ(r.epoch.frame.position, r.prev.frame.position);
  EXPECT_EQ(r.epoch.spectrum.u, r.prev.spectrum.u);
  EXPECT_EQ(r.epoch.focus.cyberank, r.prev.focus.cyberank);
}

// What an epoch carries for the next one's certificate (R1-INC-038) is, after every epoch of a
// chain, exactly what one pass over every particle of its own graph gives: the image numerators
// of L~ u and the three sums per vector. The chain adds links, reweights, adds a particle and
// drops one, at h = 0, 1 and 2, so rows of F and rows reached only through N_h both change.
// The carried image, residual sums and sum of phi ln phi (R1-INC-038, R1-INC-054) equal passes over
// the whole graph along a chain with added, reweighted and removed links and particles, read back
// from their directories at each link.
TEST(Incremental, TheCarriedImageAndSumsAreTheWholeGraphsBitForBit) {
  r1::Snapshot s = rgg(1200, 5);
  r1::Epoch prev = full_epoch(s);
  const auto check = [](const r1::Epoch& e, const r1::Graph& g, const std::string& what) {
    auto op = r1::spectral_operator_q32(g, r1::SpectralParams{});
    ASSERT_TRUE(op.is_ok());
    ASSERT_GE(e.spectrum.sums_shift, 0) << what;
    std::vector<r1::i128> image;
    r1::spectral::ResidualSums sums;
    r1::spectral::image_and_sums(*op, e.spectrum.u, op->e / 2, image, sums);
    EXPECT_EQ(e.spectrum.sums_shift, op->e / 2) << what;
    EXPECT_TRUE(image == e.spectrum.image) << what;
    EXPECT_TRUE(sums == e.spectrum.sums) << what;
    r1::fx::ExactSum plogp;
    for (const r1::Q32 x : e.focus.phi) plogp.add_term(r1::phi_log_phi(x));
    EXPECT_EQ(e.focus.plogp, std::optional<r1::fx::ExactSum>(plogp)) << what;
  };
  check(prev, graph(s), "the full epoch");
  const r1::Anchor anchor = r1::make_anchor(s, prev.frame);
  for (std::uint32_t hops = 0; hops < 3; ++hops) {
    const std::size_t k = 40 + 97 * hops;
    std::string batch = "reweight\t" + s.names[s.links[k].from] + "\t" + s.names[s.links[k].to] + "\t0.75\n";
    batch += "add\t" + s.names[1100 - hops] + "\t" + s.names[1030 + hops] + "\t0.5\n";
    batch += "add\t" + s.names[1050] + "\tnewcomer" + std::to_string(hops) + "\t0.5\n";
    if (hops == 1) {
      const std::string lone = s.names.back();
      for (const r1::Link& l : s.links)
        if (s.names[l.from] == lone || s.names[l.to] == lone) batch += "remove\t" + s.names[l.from] + "\t" + s.names[l.to] + "\n";
    }
    r1::Snapshot next = edited(s, batch);
    const r1::Graph g = graph(next);
    r1::UpdateOptions uo;
    uo.hops = hops;
    uo.keep_local = true;
    uo.full_norm = 1000;  // new low-degree links move L~ by more than R-1.0's 0.05
    r1::ReferenceStages stages;
    auto e = r1::run_epoch_from(prev, anchor, "prev", next, g, r1::EpochOptions{}, uo, stages);
    ASSERT_TRUE(e.is_ok()) << e.status().message();
    ASSERT_TRUE(e->update->incremental) << e->update->reason;
    check(*e, g, "h = " + std::to_string(hops));
    // The next link of the chain reads it back from its directory (manifest and image.i128).
    const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / ("carried-" + std::to_string(hops));
    std::filesystem::remove_all(dir);
    ASSERT_TRUE(r1::write_epoch(*e, dir).is_ok());
    auto back = r1::read_epoch(dir);
    ASSERT_TRUE(back.is_ok()) << back.status().message();
    EXPECT_TRUE(back->spectrum.image == e->spectrum.image);
    EXPECT_TRUE(back->spectrum.sums == e->spectrum.sums);
    EXPECT_EQ(back->spectrum.sums_shift, e->spectrum.sums_shift);
    EXPECT_EQ(back->focus.plogp, e->focus.plogp);
    ASSERT_TRUE(e->update->focus_local);
    prev = std::move(*back);
    s = std::move(next);
  }
}

TEST(Incremental, CertifiedUpdateBoundsTheExactEigenvectorsAndFreezesTheRest) {
  r1::UpdateOptions uo;
  uo.hops = 3;
  const UpdateRun r = incremental_run(small_reweight, uo);
  ASSERT_TRUE(r.epoch.update.has_value());
  const r1::UpdateInfo& u = *r.epoch.update;
  ASSERT_TRUE(u.incremental) << u.reason;
  EXPECT_EQ(u.touched, 2u);
  EXPECT_EQ(u.epochs_since_full, 1u);
  EXPECT_LE(u.certificate, u.eps_x);
  const std::vector<std::uint32_t> nh = r1::neighbourhood(r.g, {r.next.links[10].from, r.next.links[10].to}, 3);
  EXPECT_EQ(u.region, nh.size());
  std::vector<char> in(r.g.n, 0);
  for (std::uint32_t i : nh) in[i] = 1;
  // Outside N_h: the earlier vectors and positions, bit for bit; inside, some moved.
  std::size_t moved = 0;
  for (std::uint32_t i = 0; i < r.g.n; ++i) {
    if (in[i]) {
      moved += r.epoch.frame.position[i] != r.prev.frame.position[i];
      continue;
    }
    ASSERT_EQ(r.epoch.frame.position[i], r.prev.frame.position[i]) << i;
    for (std::size_t c = 0; c < 5; ++c) ASSERT_EQ(r.epoch.spectrum.u[c][i], r.prev.spectrum.u[c][i]);
    ASSERT_EQ(r.epoch.focus.phi[i], r.prev.focus.phi[i]) << i;  // R1-INC-050: phi frozen too
  }
  EXPECT_GT(moved, 0u);
  // phi on N_h only, conserved exactly, every raw positive, and nearer the edited graph's full
  // focus than the earlier phi is.
  EXPECT_TRUE(u.focus_local);
  std::int64_t total = 0;
  for (const r1::Q32 x : r.epoch.focus.phi) {
    ASSERT_GE(x.raw, 1);
    total += x.raw;
  }
  EXPECT_EQ(total, std::int64_t{1} << 32);
  auto full_focus = r1::compute_focus_q32(r.g, r1::TriKernelParams{}, r.epoch.spectrum.eigenvalues[1]);
  ASSERT_TRUE(full_focus.is_ok());
  double left = 0, moved_phi = 0;
  for (std::uint32_t i = 0; i < r.g.n; ++i) {
    left += std::fabs(r.epoch.focus.phi[i].to_double() - full_focus->phi[i].to_double());
    moved_phi += std::fabs(r.prev.focus.phi[i].to_double() - full_focus->phi[i].to_double());
  }
  EXPECT_LT(left, moved_phi);
  std::ostringstream said;
  said << std::scientific << left << " of " << moved_phi;
  RecordProperty("focus_l1_left", said.str());
  // The exact eigenvectors of the operator (dense, Eigen): each updated vector lies within its
  // bound of the sign-matched one.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(dense_operator(r.g));
  for (std::size_t c = 0; c < 4; ++c) {
    Eigen::VectorXd x(r.g.n);
    for (std::uint32_t i = 0; i < r.g.n; ++i) x[i] = r.epoch.spectrum.u[c][i].to_double();
    Eigen::VectorXd star = eig.eigenvectors().col(static_cast<Eigen::Index>(c + 1));
    if (x.dot(star) < 0) star = -star;
    const double err = (x - star).norm();
    EXPECT_LE(err, u.vector_bound[c]) << "u_" << c + 2;
    EXPECT_NEAR(r.epoch.spectrum.eigenvalues[c + 1], eig.eigenvalues()[static_cast<Eigen::Index>(c + 1)], 1e-9);
  }
  // The position certificate is the vector bounds through the frame's scale.
  const double s = r.prev.frame.scale * (r.prev.frame.alignment.genesis ? 1.0 : r.prev.frame.alignment.scale);
  EXPECT_NEAR(u.certificate,
              s * std::sqrt(u.vector_bound[0] * u.vector_bound[0] + u.vector_bound[1] * u.vector_bound[1] +
                            u.vector_bound[2] * u.vector_bound[2]) + 1e-6,
              1e-9 * u.certificate);
  // The hierarchy (R1-INC-035): the levels of the new positions built at PREV's r_0, no search.
  EXPECT_TRUE(u.hierarchy_radius_kept);
  r1::HierarchyOptions at_prev;
  at_prev.radius0_raw = r.prev.hierarchy.radius_raw[0];
  auto h = r1::build_hierarchy(r.epoch.frame.position, r.epoch.focus.phi, r.epoch.encoding.color, r.epoch.ids, at_prev);
  ASSERT_TRUE(h.is_ok()) << h.status().message();
  EXPECT_EQ(r1::hierarchy_bytes(*h), r1::hierarchy_bytes(r.epoch.hierarchy));
  // The encoding's r_0 (R1-INC-035): PREV's, and every radius follows from it as in a full encoding.
  EXPECT_TRUE(u.radius_scale_kept);
  EXPECT_EQ(r.epoch.encoding.radius_scale, "spacing");
  EXPECT_EQ(r.epoch.encoding.r0_squared_raw, r.prev.encoding.r0_squared_raw);
  for (std::size_t p = 0; p < r.epoch.ids.size(); ++p)
    ASSERT_EQ(r.epoch.encoding.radius[p].raw, r1::radius_of(r.epoch.focus.phi[p], r1::Q32::one(), r.prev.encoding.r0_squared_raw).raw) << p;
  // The same inputs, the same bytes.
  const UpdateRun again = incremental_run(small_reweight, uo);
  EXPECT_EQ(*r1::epoch_files(again.epoch), *r1::epoch_files(r.epoch));
}

TEST(Incremental, FullSolveWhenTheCertificateFailsOrTheCadenceSaysSo) {
  // A 1% reweight moves u_2..u_4 by more than the local update can follow within eps_X.
  r1::UpdateOptions uo;
  uo.hops = 3;
  const UpdateRun big = incremental_run([](const r1::Snapshot& s) { return reweight(s, "0.99"); }, uo);
  ASSERT_TRUE(big.epoch.update.has_value());
  EXPECT_FALSE(big.epoch.update->incremental);
  EXPECT_EQ(big.epoch.update->reason.rfind("certificate ", 0), 0u) << big.epoch.update->reason;
  EXPECT_EQ(big.epoch.update->epochs_since_full, 0u);
  EXPECT_EQ(big.epoch.update->full_eigenvalues, big.epoch.spectrum.eigenvalues);
  EXPECT_FALSE(big.epoch.update->hierarchy_radius_kept);  // a full solve searches r_0 (R1-INC-035)
  EXPECT_FALSE(big.epoch.update->radius_scale_kept);      // and measures the encoding's r_0 again
  EXPECT_EQ(big.epoch.encoding.r0_squared_raw,
            r1::radius_scale_from_layout(big.epoch.frame.position, big.epoch.focus.phi).r0_squared_raw);
  // The full solve is the epoch aligned to the earlier anchor, byte for byte.
  r1::EpochOptions o;
  o.anchor = r1::make_anchor(big.s, big.prev.frame);
  o.anchor_name = "prev/anchor.bin";
  auto plain = r1::run_epoch(big.next, big.g, o);
  ASSERT_TRUE(plain.is_ok());
  EXPECT_EQ(*r1::epoch_files(*plain), *r1::epoch_files(big.epoch));
  // Removing a link between low-degree particles moves the operator by more than R-1.0's 0.05.
  const UpdateRun cut = incremental_run(
      [](const r1::Snapshot& s) { return "remove\t" + s.names[s.links[0].from] + "\t" + s.names[s.links[0].to] + "\n"; }, uo);
  EXPECT_EQ(cut.epoch.update->reason.find("||L~ - L~_full|| bound "), 0u) << cut.epoch.update->reason;

  r1::UpdateOptions every;
  every.hops = 3;
  every.full_every = 1;
  const UpdateRun cadence = incremental_run(small_reweight, every);
  EXPECT_EQ(cadence.epoch.update->reason, "cadence: 1 epochs since the last full solve");
  r1::UpdateOptions wide;  // the default h = 9 covers most of a 1000-particle rgg graph
  const UpdateRun covered = incremental_run(small_reweight, wide);
  EXPECT_EQ(covered.epoch.update->hops, 9u);
  EXPECT_NE(covered.epoch.update->reason.find("N_h (9 hops) holds"), std::string::npos) << covered.epoch.update->reason;
}

TEST(Incremental, PropertyCertificatesBoundTheExactEigenvectorsAndFocusIsConserved) {
  // Random rgg graphs and small random reweights: whatever the update decides, an incremental
  // epoch's vectors lie within their bounds of the dense solve's, focus sums to exactly 1 with
  // every entry positive, and the same inputs give the same bytes.
  std::size_t incremental = 0;
  EXPECT_TRUE(r1::test::check_cases("incremental certificate", 8, [&] {
    const auto seed = *rc::gen::inRange<std::uint64_t>(1, 1000);
    const auto links = *rc::gen::container<std::vector<std::size_t>>(*rc::gen::inRange<std::size_t>(1, 4),
                                                                      rc::gen::inRange<std::size_t>(0, 2000));
    const auto permille = *rc::gen::inRange(990, 1000);
    const r1::Snapshot s = rgg(400, seed, 0.25);  // mean degree about 25: connected
    std::string batch;
    std::set<std::pair<std::uint32_t, std::uint32_t>> used;
    for (std::size_t k : links) {
      const r1::Link& l = s.links[k % s.links.size()];
      if (!used.insert({l.from, l.to}).second) continue;
      batch += "reweight\t" + s.names[l.from] + "\t" + s.names[l.to] + "\t0." + std::to_string(permille) + "\n";
    }
    RC_LOG() << "rgg 400 radius 0.25 seed " << seed << ": " << batch;
    const r1::Epoch prev = full_epoch(s);
    const r1::Snapshot next = edited(s, batch);
    const r1::Graph g = graph(next);
    const r1::Anchor anchor = r1::make_anchor(s, prev.frame);
    r1::ReferenceStages stages;
    r1::UpdateOptions uo;
    uo.hops = 3;
    uo.eps = 0.5;  // accept loose certificates too: the property is that they bound
    auto e = r1::run_epoch_from(prev, anchor, "prev", next, g, r1::EpochOptions{}, uo, stages);
    RC_ASSERT(e.is_ok());
    std::int64_t total = 0;
    for (const r1::Q32 phi : e->focus.phi) {
      RC_ASSERT(phi.raw > 0);
      total += phi.raw;
    }
    RC_ASSERT(total == r1::Q32::kOneRaw);
    auto again = r1::run_epoch_from(prev, anchor, "prev", next, g, r1::EpochOptions{}, uo, stages);
    RC_ASSERT(again.is_ok());
    RC_ASSERT(*r1::epoch_files(*again) == *r1::epoch_files(*e));
    if (!e->update->incremental) return;
    ++incremental;
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(dense_operator(g));
    for (std::size_t c = 0; c < 4; ++c) {
      if (!std::isfinite(e->update->vector_bound[c])) continue;
      Eigen::VectorXd x(g.n);
      for (std::uint32_t i = 0; i < g.n; ++i) x[i] = e->spectrum.u[c][i].to_double();
      Eigen::VectorXd star = eig.eigenvectors().col(static_cast<Eigen::Index>(c + 1));
      if (x.dot(star) < 0) star = -star;
      RC_ASSERT((x - star).norm() <= e->update->vector_bound[c]);
    }
  }));
  RecordProperty("incremental_cases", static_cast<int>(incremental));
}

}  // namespace
