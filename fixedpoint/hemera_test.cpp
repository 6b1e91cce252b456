// Hemera tests (R1-HASH-001..022): published vectors, streaming, tree shape, domain separation,
// and the batched paths against the one-at-a-time definition.
#include "r1/fixedpoint/hemera.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>
#include <tbb/task_arena.h>

#include <fstream>
#include <numeric>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hemera_constants.inc"
#include "hemera_internal.hpp"
#include "test_support.hpp"

namespace {

namespace hm = r1::hemera;
namespace gl = r1::gl;
using Bytes = std::vector<std::uint8_t>;
using gl::Fp;

std::span<const std::uint8_t> span_of(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

nlohmann::json vectors() {
  return nlohmann::json::parse(r1::test::read_file(r1::test::source_dir() / "tests/data/hemera_vectors.json"));
}

TEST(Hemera, PublishedPlainVectors) {
  const auto v = vectors();
  EXPECT_EQ(hm::to_hex(hm::hash("")), v["hash"]["empty"]);
  EXPECT_EQ(hm::to_hex(hm::hash("hello")), v["hash"]["hello"]);
  EXPECT_EQ(hm::to_hex(hm::hash("hemera")), v["hash"]["hemera"]);
}

TEST(Hemera, PublishedTreeVectors) {
  const auto v = vectors();
  EXPECT_EQ(hm::to_hex(hm::root_hash(span_of(""))), v["tree"]["empty"]);
  EXPECT_EQ(hm::to_hex(hm::root_hash(span_of("hello"))), v["tree"]["hello"]);
  const Bytes zeros(4096, 0);
  EXPECT_EQ(hm::to_hex(hm::root_hash(zeros)), v["tree"]["4k_zeros"]);
}

TEST(Hemera, PublishedDeriveKeyVector) {
  const auto v = vectors();
  EXPECT_EQ(hm::to_hex(hm::derive_key("test context", span_of("test material"))), v["derive_key"]["test"]);
}

TEST(Hemera, CommittedVectorsMatchSharedCopy) {
  const auto shared = r1::test::shared_data_dir();
  if (shared.empty()) GTEST_SKIP() << "../shared/data is not beside this checkout";
  EXPECT_EQ(nlohmann::json::parse(r1::test::read_file(shared / "hemera_vectors.json")), vectors());
}

TEST(Hemera, ConstantsMatchSharedTable) {
  const auto shared = r1::test::shared_data_dir();
  if (shared.empty()) GTEST_SKIP() << "../shared/data is not beside this checkout";
  // Regenerating the include from the shared table must give the committed file.
  const std::string cmd = "python3 " + (r1::test::source_dir() / "scripts/gen-hemera-constants.py").string() + " " +
                          (shared / "hemera_constants.tsv").string();
  FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof buf, p)) out.append(buf, n);
  ASSERT_EQ(::pclose(p), 0);
  EXPECT_EQ(out, r1::test::read_file(r1::test::source_dir() / "fixedpoint/hemera_constants.inc"));
}

RC_GTEST_PROP(Hemera, StreamingEqualsOneShot, (const Bytes& data)) {
  const std::size_t cut1 = *rc::gen::inRange<std::size_t>(0, data.size() + 1);
  const std::size_t cut2 = *rc::gen::inRange<std::size_t>(cut1, data.size() + 1);
  hm::Hasher h;
  h.update(std::span(data).subspan(0, cut1));
  h.update(std::span(data).subspan(cut1, cut2 - cut1));
  h.update(std::span(data).subspan(cut2));
  RC_ASSERT(h.finalize() == hm::hash(data));
}

TEST(Hemera, PaddingBoundariesAllDiffer) {
  // Lengths around the 56-byte rate and trailing zeros: all digests distinct.
  std::vector<hm::Digest> seen;
  for (std::size_t n : {0, 1, 55, 56, 57, 111, 112, 113}) {
    const Bytes zeros(n, 0);
    seen.push_back(hm::hash(zeros));
  }
  for (std::size_t i = 0; i < seen.size(); ++i)
    for (std::size_t j = i + 1; j < seen.size(); ++j) EXPECT_NE(seen[i], seen[j]) << i << " " << j;
}

TEST(Hemera, DomainsSeparate) {
  const std::string msg = "test data";
  const hm::Digest key{};
  EXPECT_NE(hm::hash(msg), hm::keyed_hash(key, span_of(msg)));
  hm::Digest key2{};
  key2[0] = 1;
  EXPECT_NE(hm::keyed_hash(key, span_of(msg)), hm::keyed_hash(key2, span_of(msg)));
  EXPECT_NE(hm::derive_key("a", span_of(msg)), hm::derive_key("b", span_of(msg)));
  // A single-chunk tree hash is the leaf with the ROOT flag, not the plain hash.
  EXPECT_NE(hm::root_hash(span_of(msg)), hm::hash(msg));
  EXPECT_EQ(hm::root_hash(span_of(msg)), hm::hash_leaf(span_of(msg), 0, true));
}

TEST(Hemera, TreeShapeIsLeftBalanced) {
  // 3 chunks: root = node(node(L0, L1), L2) with ROOT only at the top (tree.md example).
  Bytes data(3 * 4096);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<std::uint8_t>(i * 31 + 7);
  const auto sp = std::span<const std::uint8_t>(data);
  const auto l0 = hm::hash_leaf(sp.subspan(0, 4096), 0, false);
  const auto l1 = hm::hash_leaf(sp.subspan(4096, 4096), 1, false);
  const auto l2 = hm::hash_leaf(sp.subspan(8192, 4096), 2, false);
  EXPECT_EQ(hm::root_hash(sp), hm::hash_node(hm::hash_node(l0, l1, false), l2, true));
  // 5 chunks plus one byte: left subtree holds 4 leaves, the right one the remaining 2.
  Bytes d6(5 * 4096 + 1, 0xAB);
  const auto s6 = std::span<const std::uint8_t>(d6);
  std::vector<hm::Digest> L;
  for (std::size_t i = 0; i < 6; ++i) L.push_back(hm::hash_leaf(s6.subspan(i * 4096, std::min<std::size_t>(4096, d6.size() - i * 4096)), i, false));
  const auto left = hm::hash_node(hm::hash_node(L[0], L[1], false), hm::hash_node(L[2], L[3], false), false);
  EXPECT_EQ(hm::root_hash(s6), hm::hash_node(left, hm::hash_node(L[4], L[5], false), true));
}

TEST(Hemera, TreeHashIndependentOfParallelism) {
  Bytes data(37 * 4096 + 123);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<std::uint8_t>((i * 2654435761u) >> 13);
  EXPECT_EQ(hm::root_hash(data, true), hm::root_hash(data, false));
}

TEST(Hemera, HexRoundTrip) {
  const auto d = hm::hash("hello");
  hm::Digest back{};
  ASSERT_TRUE(hm::from_hex(hm::to_hex(d), back));
  EXPECT_EQ(back, d);
  EXPECT_FALSE(hm::from_hex("zz", back));
  EXPECT_FALSE(hm::from_hex(std::string(64, 'g'), back));
}


// ---------------------------------------------------------------------------------------------
// The permutation as the spec writes it (R1-HASH-002), in canonical gl:: arithmetic, one layer at
// a time; the optimised permute() and the lane-batched path are checked against it.
namespace ref {

using Layer = void (*)(hm::State&);
Fp F(std::uint64_t x) { return Fp::from_u64(x); }

void external(hm::State& s) {
  Fp t[16];
  for (std::size_t g = 0; g < 4; ++g) {
    const Fp a = F(s[4 * g]), b = F(s[4 * g + 1]), c = F(s[4 * g + 2]), d = F(s[4 * g + 3]);
    const Fp sum = gl::add(gl::add(a, b), gl::add(c, d));
    t[4 * g + 0] = gl::add(gl::add(sum, a), gl::add(b, b));  // [2 3 1 1]
    t[4 * g + 1] = gl::add(gl::add(sum, b), gl::add(c, c));  // [1 2 3 1]
    t[4 * g + 2] = gl::add(gl::add(sum, c), gl::add(d, d));  // [1 1 2 3]
    t[4 * g + 3] = gl::add(gl::add(sum, d), gl::add(a, a));  // [3 1 1 2]
  }
  for (std::size_t j = 0; j < 4; ++j) {
    const Fp col = gl::add(gl::add(t[j], t[4 + j]), gl::add(t[8 + j], t[12 + j]));
    for (std::size_t g = 0; g < 4; ++g) s[4 * g + j] = gl::add(t[4 * g + j], col).v;
  }
}

void internal(hm::State& s) {
  Fp sum{};
  for (std::size_t i = 0; i < 16; ++i) sum = gl::add(sum, F(s[i]));
  for (std::size_t i = 0; i < 16; ++i) s[i] = gl::add(gl::mul(F(hm::detail::kInternalDiag[i]), F(s[i])), sum).v;
}

Fp sbox7(Fp x) { return gl::pow(x, 7); }

void full_round(hm::State& s, std::size_t r) {
  for (std::size_t i = 0; i < 16; ++i) s[i] = sbox7(gl::add(F(s[i]), F(hm::detail::kRoundFull[16 * r + i]))).v;
  external(s);
}

// Records in `zeros` each partial round whose S-box input is 0.
void partial_round(hm::State& s, std::size_t r, std::vector<std::size_t>* zeros) {
  const Fp x = gl::add(F(s[0]), F(hm::detail::kRoundPartial[r]));
  if (x.v == 0 && zeros) zeros->push_back(r);
  s[0] = gl::pow_p_minus_2(x).v;
  internal(s);
}

hm::State permute(hm::State s, std::vector<std::size_t>* zeros = nullptr) {
  external(s);
  for (std::size_t r = 0; r < 4; ++r) full_round(s, r);
  for (std::size_t r = 0; r < 16; ++r) partial_round(s, r, zeros);
  for (std::size_t r = 4; r < 8; ++r) full_round(s, r);
  return s;
}

// Inverse of a linear layer over F_p, by Gauss-Jordan elimination on its 16x16 matrix (column j
// is the layer applied to the j-th unit vector).
using Matrix = std::array<std::array<Fp, 16>, 16>;
Matrix inverse_of(Layer layer) {
  Matrix m{}, inv{};
  for (std::size_t j = 0; j < 16; ++j) {
    hm::State e{};
    e[j] = 1;
    layer(e);
    for (std::size_t i = 0; i < 16; ++i) m[i][j] = F(e[i]);
    inv[j][j] = F(1);
  }
  for (std::size_t c = 0; c < 16; ++c) {
    std::size_t piv = c;
    while (m[piv][c].v == 0) ++piv;
    std::swap(m[piv], m[c]);
    std::swap(inv[piv], inv[c]);
    const Fp k = *gl::inverse(m[c][c]);
    for (std::size_t j = 0; j < 16; ++j) m[c][j] = gl::mul(m[c][j], k), inv[c][j] = gl::mul(inv[c][j], k);
    for (std::size_t i = 0; i < 16; ++i) {
      if (i == c || m[i][c].v == 0) continue;
      const Fp f = m[i][c];
      for (std::size_t j = 0; j < 16; ++j) {
        m[i][j] = gl::sub(m[i][j], gl::mul(f, m[c][j]));
        inv[i][j] = gl::sub(inv[i][j], gl::mul(f, inv[c][j]));
      }
    }
  }
  return inv;
}

void apply(const Matrix& m, hm::State& s) {
  hm::State out{};
  for (std::size_t i = 0; i < 16; ++i) {
    Fp acc{};
    for (std::size_t j = 0; j < 16; ++j) acc = gl::add(acc, gl::mul(m[i][j], F(s[j])));
    out[i] = acc.v;
  }
  s = out;
}

// 7^-1 mod (p - 1): x -> x^7 is a bijection because gcd(7, p - 1) = 1.
std::uint64_t inverse_of_7() {
  for (r1::u128 k = 0; k < 7; ++k) {
    const r1::u128 v = k * (gl::P - 1) + 1;
    if (v % 7 == 0) return static_cast<std::uint64_t>(v / 7);
  }
  return 0;
}

// A permutation input whose S-box input in partial round r is 0: pick the state entering that
// round with s[0] = -RC[r], then undo the layers before it.
hm::State input_zeroing_round(std::size_t r, hm::State at_round) {
  static const Matrix ext_inv = inverse_of(&external);
  static const Matrix int_inv = inverse_of(&internal);
  static const std::uint64_t e7 = inverse_of_7();
  hm::State s = at_round;
  s[0] = gl::neg(F(hm::detail::kRoundPartial[r])).v;
  for (std::size_t i = 1; i < 16; ++i) s[i] = F(s[i]).v;
  for (std::size_t j = r; j-- > 0;) {
    apply(int_inv, s);
    s[0] = gl::sub(gl::pow_p_minus_2(F(s[0])), F(hm::detail::kRoundPartial[j])).v;  // x^(p-2) undoes itself
  }
  for (std::size_t j = 4; j-- > 0;) {
    apply(ext_inv, s);
    for (std::size_t i = 0; i < 16; ++i) s[i] = gl::sub(gl::pow(F(s[i]), e7), F(hm::detail::kRoundFull[16 * j + i])).v;
  }
  apply(ext_inv, s);
  return s;
}

}  // namespace ref

// Values near 0, p and 2^64 matter most for carries and for the lazy representatives.
rc::Gen<std::uint64_t> edgy_word() {
  return rc::gen::oneOf(
      rc::gen::arbitrary<std::uint64_t>(), rc::gen::inRange<std::uint64_t>(0, 1u << 16),
      rc::gen::map(rc::gen::inRange<std::uint64_t>(0, 1u << 16), [](std::uint64_t d) { return gl::P - 1 + d; }),
      rc::gen::map(rc::gen::inRange<std::uint64_t>(0, 1u << 16),
                   [](std::uint64_t d) { return ~std::uint64_t{0} - d; }));
}

rc::Gen<hm::State> any_state() { return rc::gen::container<hm::State>(edgy_word()); }

hm::State canonical(hm::State s) {
  for (auto& w : s) w = Fp::from_u64(w).v;
  return s;
}

// Turns a process-wide switch on or off for one scope.
template <bool (*Get)(), void (*Set)(bool)>
class Switch {
 public:
  explicit Switch(bool on) : was_(Get()) { Set(on); }
  ~Switch() { Set(was_); }
  Switch(const Switch&) = delete;
  Switch& operator=(const Switch&) = delete;

 private:
  bool was_;
};
using Batching = Switch<hm::lane_batching, hm::set_lane_batching>;
using VectorRounds = Switch<hm::vector_rounds, hm::set_vector_rounds>;

RC_GTEST_PROP(HemeraLazy, ReduceFoldMulAddAreCongruent, ()) {
  namespace lz = hm::detail::lazy;
  const std::uint64_t a = *edgy_word(), b = *edgy_word(), c = *edgy_word();
  const r1::u128 x = (static_cast<r1::u128>(a) << 64) | b;
  RC_ASSERT(gl::canonical(lz::reduce(x)) == gl::reduce128(x).v);
  RC_ASSERT(gl::canonical(lz::mul(a, b)) == gl::mul(Fp::from_u64(a), Fp::from_u64(b)).v);
  const r1::u128 small = static_cast<r1::u128>(a) + b + c + (static_cast<r1::u128>(c) << 5);  // < 2^70
  RC_ASSERT(gl::canonical(lz::fold(small)) == gl::reduce128(small).v);
  const std::uint64_t k = Fp::from_u64(c).v;
  RC_ASSERT(gl::canonical(lz::add_canonical(a, k)) == gl::add(Fp::from_u64(a), Fp::from_u64(k)).v);
}

TEST(HemeraLazy, InvertLanesHandlesZeroLanes) {
  // Zero (as 0 and as its other representative p) at the first, a middle and the last lane, and
  // every lane zero: the product must not be poisoned, zeros map to zero.
  std::uint64_t x[16], want[16];
  const std::vector<std::vector<std::size_t>> zero_sets = {{}, {0}, {7}, {15}, {0, 15}, {3, 4, 5},
                                                            {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15}};
  for (std::size_t t = 0; t < zero_sets.size(); ++t) {
    for (std::size_t k = 0; k < 16; ++k) x[k] = 0x9E3779B97F4A7C15ull * (k + 1 + 16 * t) + (k % 3 == 0 ? gl::P : 0);
    for (std::size_t z : zero_sets[t]) x[z] = (z % 2 == 0) ? 0 : gl::P;
    for (std::size_t k = 0; k < 16; ++k) want[k] = gl::pow_p_minus_2(Fp::from_u64(x[k])).v;
    hm::detail::lazy::invert_lanes<16>(x);
    for (std::size_t k = 0; k < 16; ++k) EXPECT_EQ(gl::canonical(x[k]), want[k]) << "set " << t << " lane " << k;
  }
}

TEST(HemeraLazy, InterleavedChainsInvertEveryLane) {
  // Two chains of 32 lanes (the 64-lane partial round) and four of 16, zeros in the first and last lane of
  // a chain, a whole chain zero, and chains that share no zero: each lane is its own x^(p-2).
  std::uint64_t x[64], want[64];
  std::vector<std::vector<std::size_t>> zero_sets = {{}, {0}, {15, 16}, {63}, {}};
  for (std::size_t k = 32; k < 48; ++k) zero_sets.back().push_back(k);  // a whole chain of the 4 x 16
  for (std::size_t t = 0; t < zero_sets.size(); ++t) {
    for (std::size_t k = 0; k < 64; ++k) x[k] = 0xD6E8FEB86659FD93ull * (k + 1 + 64 * t) + (k % 5 == 0 ? gl::P : 0);
    for (std::size_t z : zero_sets[t]) x[z] = (z % 2 == 0) ? 0 : gl::P;
    for (std::size_t k = 0; k < 64; ++k) want[k] = gl::pow_p_minus_2(Fp::from_u64(x[k])).v;
    std::uint64_t y[64];
    std::copy(x, x + 64, y);
    hm::detail::lazy::invert_chains<2, 32>(x);
    hm::detail::lazy::invert_chains<4, 16>(y);
    for (std::size_t k = 0; k < 64; ++k) EXPECT_EQ(gl::canonical(x[k]), want[k]) << "set " << t << " lane " << k;
    for (std::size_t k = 0; k < 64; ++k) EXPECT_EQ(gl::canonical(y[k]), want[k]) << "set " << t << " lane " << k;
  }
}

RC_GTEST_PROP(Hemera, PermuteMatchesReference, ()) {
  const hm::State s = *any_state();
  hm::State fast = s;
  hm::permute(fast);
  RC_ASSERT(fast == ref::permute(canonical(s)));
}

RC_GTEST_PROP(Hemera, PermuteManyMatchesScalar, ()) {
  // Any count: 64-lane groups plus 32, 16, 8, 4, 2, 1 for the rest.
  const auto count = *rc::gen::inRange<std::size_t>(0, 200);
  const auto states = *rc::gen::container<std::vector<hm::State>>(count, any_state());
  std::vector<hm::State> batched = states;
  const std::uint64_t before = hm::detail::lane_batches();
  hm::permute_many(batched);
  for (std::size_t k = 0; k < states.size(); ++k) {
    hm::State one = states[k];
    hm::permute(one);
    RC_ASSERT(batched[k] == one);
  }
  if (states.size() >= 2) RC_ASSERT(hm::detail::lane_batches() > before);  // the lane path ran
}

// R1-HASH-023: the AVX-512 rounds are the scalar rounds, for one state and in lanes, on any
// words (edgy ones included: p, p - 1, 2^64 - 1, 0, ...), the batch sizes 1 to 64 and more; and
// the element-major sponge (hash_many) is the one-state-at-a-time scalar sponge.

RC_GTEST_PROP(Hemera, VectorRoundsAreTheScalarRounds, ()) {
  {
    VectorRounds on(true);
    if (!hm::vector_rounds()) RC_SUCCEED("this CPU has no AVX-512: the scalar rounds are the only ones");
  }
  const auto count = *rc::gen::inRange<std::size_t>(1, 200);
  const auto states = *rc::gen::container<std::vector<hm::State>>(count, any_state());
  std::vector<hm::State> vec = states, scalar = states;
  {
    VectorRounds on(true);
    hm::permute_many(vec);
    hm::State one = states[0];
    hm::permute(one);
    RC_ASSERT(one == vec[0]);
  }
  {
    VectorRounds off(false);
    RC_ASSERT(!hm::vector_rounds());
    hm::permute_many(scalar);
  }
  RC_ASSERT(vec == scalar);
}

TEST(Hemera, ZeroSboxInputInLanes) {
  // States whose partial-round S-box input is exactly 0, in chosen lanes of 64-, 32-, 16-, 8-, 4-
  // and 2-lane groups, among ordinary states; and every lane zero in the same round.
  for (std::size_t round : {0u, 6u, 15u}) {
    for (std::size_t n : {64u, 63u, 16u, 15u, 2u}) {
      for (const std::vector<std::size_t>& zero_lanes :
           std::vector<std::vector<std::size_t>>{{0}, {n - 1}, {n / 2}, {0, n - 1}, {}}) {
        std::vector<hm::State> states(n);
        for (std::size_t k = 0; k < n; ++k)
          for (std::size_t i = 0; i < 16; ++i) states[k][i] = 0xD1B54A32D192ED03ull * (k * 16 + i + 1) + round;
        std::vector<std::size_t> zeros_expected;
        const bool all = zero_lanes.empty();
        for (std::size_t k = 0; k < n; ++k) {
          if (all || std::find(zero_lanes.begin(), zero_lanes.end(), k) != zero_lanes.end())
            states[k] = ref::input_zeroing_round(round, states[k]);
        }
        std::vector<hm::State> batched = states;
        hm::permute_many(batched);
        for (std::size_t k = 0; k < n; ++k) {
          std::vector<std::size_t> zeros;
          const hm::State want = ref::permute(states[k], &zeros);
          const bool zeroed = all || std::find(zero_lanes.begin(), zero_lanes.end(), k) != zero_lanes.end();
          // The construction really reaches a zero S-box input in that round.
          if (zeroed) {
            EXPECT_EQ(zeros, std::vector<std::size_t>{round}) << "lane " << k;
          }
          hm::State one = states[k];
          hm::permute(one);
          EXPECT_EQ(one, want) << "scalar, round " << round << " n " << n << " lane " << k;
          EXPECT_EQ(batched[k], want) << "batched, round " << round << " n " << n << " lane " << k;
        }
      }
    }
  }
}

std::vector<Bytes> mixed_inputs(std::size_t count, std::uint64_t seed) {
  static const std::size_t lengths[] = {0, 1, 7, 55, 56, 57, 111, 112, 113, 4095, 4096, 4097};
  std::vector<Bytes> v(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint64_t r = (seed + i) * 0x9E3779B97F4A7C15ull;
    const std::size_t len = (r >> 60) < 12 ? lengths[(r >> 60)] : (r >> 20) % 300;
    v[i].resize(len);
    for (std::size_t j = 0; j < len; ++j) v[i][j] = static_cast<std::uint8_t>((r >> (j % 50)) + j);
  }
  return v;
}

TEST(Hemera, HashManyEqualsHashOnMixedLengths) {
  const auto inputs = mixed_inputs(500, 11);
  std::vector<std::span<const std::uint8_t>> spans(inputs.begin(), inputs.end());
  std::vector<hm::Digest> want(inputs.size());
  for (std::size_t i = 0; i < inputs.size(); ++i) want[i] = hm::hash(inputs[i]);
  for (bool batching : {true, false}) {
    for (bool parallel : {true, false}) {
      Batching b(batching);
      const std::uint64_t before = hm::detail::lane_batches();
      std::vector<hm::Digest> got(inputs.size());
      hm::hash_many(spans, got, parallel);
      EXPECT_EQ(got, want) << "batching " << batching << " parallel " << parallel;
      // The switch decides which path runs (500 inputs share block counts, so lanes exist).
      EXPECT_EQ(hm::detail::lane_batches() > before, batching);
    }
  }
}

RC_GTEST_PROP(Hemera, HashManyEqualsHash, (const std::vector<Bytes>& some)) {
  // Random inputs plus copies at the lengths where the block count changes.
  std::vector<Bytes> inputs = some;
  for (std::size_t len : {0, 55, 56, 57, 4096}) inputs.emplace_back(len, static_cast<std::uint8_t>(len));
  std::vector<std::span<const std::uint8_t>> spans(inputs.begin(), inputs.end());
  std::vector<hm::Digest> got(inputs.size());
  hm::hash_many(spans, got, *rc::gen::arbitrary<bool>());
  for (std::size_t i = 0; i < inputs.size(); ++i) RC_ASSERT(got[i] == hm::hash(inputs[i]));
}

TEST(Hemera, ElementMajorSpongeEqualsOneStateSponge) {
  // 75 inputs of each of three block counts (0, 2 and 73 full blocks): 64-lane groups with 8- and
  // 2-lane rests. Bytes of 0xFF make rate chunks of 2^56 - 1 and carry the field additions; each
  // input has its own bytes so that a lane reading its neighbour's data shows.
  std::vector<Bytes> inputs;
  for (const std::size_t base : {0u, 112u, 4088u})
    for (std::size_t k = 0; k < 75; ++k) {
      Bytes b(base + (k * 7) % 56);
      for (std::size_t j = 0; j < b.size(); ++j)
        b[j] = (k % 3 == 0) ? 0xFF : static_cast<std::uint8_t>((j * 131 + k * 29 + base) >> (j % 3));
      inputs.push_back(std::move(b));
    }
  std::vector<hm::Digest> want(inputs.size());
  {
    VectorRounds off(false);
    for (std::size_t i = 0; i < inputs.size(); ++i) want[i] = hm::hash(inputs[i]);
  }
  std::vector<std::span<const std::uint8_t>> spans(inputs.begin(), inputs.end());
  for (const bool vector : {true, false}) {
    VectorRounds v(vector);
    std::vector<hm::Digest> got(inputs.size());
    hm::hash_many(spans, got, false);
    for (std::size_t i = 0; i < inputs.size(); ++i) EXPECT_EQ(got[i], want[i]) << "input " << i << " vector " << vector;
  }
}

TEST(Hemera, HashManyStringsEqualsHash) {
  std::vector<std::string> names;
  for (std::size_t i = 0; i < 300; ++i)
    names.push_back(std::string(i % 70, static_cast<char>('a' + i % 26)) + std::to_string(i));
  std::vector<hm::Digest> got(names.size());
  hm::hash_many(names, got);
  for (std::size_t i = 0; i < names.size(); ++i) EXPECT_EQ(got[i], hm::hash(names[i])) << names[i];
  hm::hash_many(std::span<const std::string>(), std::span<hm::Digest>());  // empty set: nothing to do
}

Bytes pattern(std::size_t n, std::uint32_t salt) {
  Bytes data(n);
  for (std::size_t i = 0; i < n; ++i) data[i] = static_cast<std::uint8_t>(((i + salt) * 2654435761u) >> 13);
  return data;
}

TEST(Hemera, TreeMatchesRecursiveDefinitionForEveryLeafCount) {
  // The level-by-level batched merge against merge_leaves' recursion: every leaf count up to 33
  // (lane groups of 16 and their remainders, odd carries at every level), around 64, and with a
  // short last chunk.
  const Bytes data = pattern(70 * 4096, 3);
  const auto sp = std::span<const std::uint8_t>(data);
  std::vector<hm::Digest> leaves;
  for (std::size_t i = 0; i < 70; ++i) leaves.push_back(hm::hash_leaf(sp.subspan(i * 4096, 4096), i, false));
  std::vector<std::size_t> counts(33);
  std::iota(counts.begin(), counts.end(), std::size_t{1});
  counts.insert(counts.end(), {47, 63, 64, 65, 70});
  for (const std::size_t n : counts) {
    const hm::Digest want = n == 1 ? hm::hash_leaf(sp.subspan(0, 4096), 0, true)
                                   : hm::detail::merge_leaves(std::span(leaves).subspan(0, n), true);
    EXPECT_EQ(hm::root_hash(sp.subspan(0, n * 4096)), want) << n << " leaves";
  }
  for (std::size_t tail : {1u, 55u, 56u, 4087u, 4088u, 4095u}) {
    const auto in = sp.subspan(0, 17 * 4096 + tail);
    std::vector<hm::Digest> l(leaves.begin(), leaves.begin() + 17);
    l.push_back(hm::hash_leaf(in.subspan(17 * 4096), 17, false));
    EXPECT_EQ(hm::root_hash(in), hm::detail::merge_leaves(l, true)) << "tail " << tail;
  }
}

RC_GTEST_PROP(Hemera, LeavesReusedFromAnEarlierVersionAreTheTreesLeaves, ()) {
  // An earlier version of 0..40 chunks (a short last chunk or none), then the version now: equal,
  // bytes changed in place, bytes inserted (every later chunk shifts), cut short or extended.
  const auto chunks = *rc::gen::inRange<std::size_t>(0, 41);
  const auto tail = *rc::gen::element<std::size_t>(0, 1, 57, 4095);
  const Bytes before = pattern(chunks * 4096 + tail, *rc::gen::inRange<std::uint32_t>(0, 1000));
  Bytes now = before;
  const int edit = *rc::gen::inRange(0, 5);
  const std::size_t at = now.empty() ? 0 : *rc::gen::inRange<std::size_t>(0, now.size());
  if (edit == 1 && !now.empty()) {
    for (int k = *rc::gen::inRange(1, 6); k > 0; --k) now[*rc::gen::inRange<std::size_t>(0, now.size())] ^= 0x5A;
  } else if (edit == 2) {
    now.insert(now.begin() + static_cast<std::ptrdiff_t>(at), *rc::gen::inRange<std::size_t>(1, 9), std::uint8_t{7});
  } else if (edit == 3) {
    now.resize(at);
  } else if (edit == 4) {
    const Bytes more = pattern(*rc::gen::inRange<std::size_t>(1, 3 * 4096), 77);
    now.insert(now.end(), more.begin(), more.end());
  }
  const std::vector<hm::Digest> prev = hm::tree_leaves(before);
  const std::vector<hm::Digest> want = hm::tree_leaves(now);
  RC_ASSERT(hm::tree_leaves_reusing(now, before, prev) == want);
  RC_ASSERT(hm::root_of_leaves(want) == hm::root_hash(now));
  RC_ASSERT(hm::root_of_leaves(prev) == hm::root_hash(before));
  // Leaves of another input (a wrong list) are refused unless their count fits `before`.
  RC_ASSERT(hm::tree_leaves_reusing(now, before, std::vector<hm::Digest>(prev.size() + 1)) == want);
}

TEST(Hemera, LeavesAreReusedOnlyWhereTheChunksAreEqual) {
  // Given stand-in leaves for the earlier version, the equal chunks take the stand-ins (so they
  // were not hashed again) and the changed ones their own digests.
  const Bytes before = pattern(10 * 4096 + 100, 5);
  Bytes now = before;
  now[3 * 4096 + 17] ^= 1;
  now[9 * 4096] ^= 1;
  std::vector<hm::Digest> stand_in(11);
  for (std::size_t i = 0; i < stand_in.size(); ++i) stand_in[i].fill(static_cast<std::uint8_t>(i + 1));
  const std::vector<hm::Digest> got = hm::tree_leaves_reusing(now, before, stand_in);
  const std::vector<hm::Digest> own = hm::tree_leaves(now);
  ASSERT_EQ(got.size(), 11u);
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i], i == 3 || i == 9 ? own[i] : stand_in[i]) << "leaf " << i;
  // One leaf on either side: the ROOT flag differs, nothing is taken.
  const Bytes small = pattern(100, 1);
  EXPECT_EQ(hm::tree_leaves_reusing(small, small, std::vector<hm::Digest>(1)), hm::tree_leaves(small));
}

TEST(Hemera, TreeIndependentOfParallelismThreadsAndBatching) {
  const Bytes data = pattern(133 * 4096 + 777, 9);
  const hm::Digest want = hm::root_hash(data, false);
  EXPECT_EQ(hm::root_hash(data, true), want);
  for (int threads : {1, 2}) {
    tbb::task_arena arena(threads);
    arena.execute([&] { EXPECT_EQ(hm::root_hash(data, true), want) << threads << " threads"; });
  }
  Batching off(false);
  EXPECT_EQ(hm::root_hash(data, true), want);
  EXPECT_EQ(hm::root_hash(data, false), want);
}

TEST(Hemera, RootHashChunksEqualsRootHash) {
  for (std::size_t n : {0u, 5u, 4096u, 4097u, 40u * 4096u + 9u}) {
    const Bytes data = pattern(n, 5);
    const auto fill = [&](std::uint64_t i, std::span<std::uint8_t> out) {
      const std::size_t off = static_cast<std::size_t>(i) * 4096, len = std::min<std::size_t>(4096, n - off);
      std::copy_n(data.begin() + static_cast<std::ptrdiff_t>(off), len, out.begin());
      return len;
    };
    EXPECT_EQ(hm::root_hash_chunks(n, fill, true), hm::root_hash(data)) << n;
    EXPECT_EQ(hm::root_hash_chunks(n, fill, false), hm::root_hash(data)) << n;
  }
}

}  // namespace
