// Hemera v2: Poseidon2 permutation over Goldilocks and the sponge/tree modes (R1-HASH-001..012).
#include "r1/fixedpoint/hemera.hpp"

#include <tbb/parallel_for.h>

#include <cstring>

#include "hemera_constants.inc"

namespace r1::hemera {

namespace {

using gl::Fp;

constexpr std::uint64_t DOMAIN_HASH = 0;
constexpr std::uint64_t DOMAIN_KEYED = 1;
constexpr std::uint64_t DOMAIN_DERIVE_CONTEXT = 2;
constexpr std::uint64_t DOMAIN_DERIVE_MATERIAL = 3;

// Capacity layout (state[8..15]): 8 chunk counter, 9 tree flags, 10 input length, 11 domain tag.
constexpr std::size_t CAP_COUNTER = 8;
constexpr std::size_t CAP_FLAGS = 9;
constexpr std::size_t CAP_LENGTH = 10;
constexpr std::size_t CAP_DOMAIN = 11;

constexpr std::uint64_t FLAG_ROOT = 1;
constexpr std::uint64_t FLAG_PARENT = 2;
constexpr std::uint64_t FLAG_CHUNK = 4;

inline Fp F(std::uint64_t x) { return Fp::from_u64(x); }

// x -> x^7 (full-round S-box).
inline Fp sbox7(Fp x) {
  const Fp x2 = gl::square(x);
  const Fp x3 = gl::mul(x2, x);
  const Fp x4 = gl::square(x2);
  return gl::mul(x3, x4);
}

// External matrix circ(2 M4, M4, M4, M4): M4 on each group of four, then each element gains the
// sum of the elements in its lane (i mod 4) over the four groups.
void external(State& s) {
  Fp t[WIDTH];
  for (std::size_t g = 0; g < 4; ++g) {
    const Fp a = F(s[4 * g]), b = F(s[4 * g + 1]), c = F(s[4 * g + 2]), d = F(s[4 * g + 3]);
    // M4 rows: [2 3 1 1], [1 2 3 1], [1 1 2 3], [3 1 1 2]
    const Fp ab = gl::add(a, b), cd = gl::add(c, d);
    const Fp sum = gl::add(ab, cd);
    t[4 * g + 0] = gl::add(gl::add(sum, a), gl::add(b, b));  // 2a + 3b + c + d
    t[4 * g + 1] = gl::add(gl::add(sum, b), gl::add(c, c));  // a + 2b + 3c + d
    t[4 * g + 2] = gl::add(gl::add(sum, c), gl::add(d, d));  // a + b + 2c + 3d
    t[4 * g + 3] = gl::add(gl::add(sum, d), gl::add(a, a));  // 3a + b + c + 2d
  }
  for (std::size_t lane = 0; lane < 4; ++lane) {
    const Fp lane_sum = gl::add(gl::add(t[lane], t[4 + lane]), gl::add(t[8 + lane], t[12 + lane]));
    for (std::size_t g = 0; g < 4; ++g) s[4 * g + lane] = gl::add(t[4 * g + lane], lane_sum).v;
  }
}

// Internal matrix: x'_i = d_i x_i + sum_j x_j.
void internal(State& s) {
  Fp sum{};
  for (std::size_t i = 0; i < WIDTH; ++i) sum = gl::add(sum, F(s[i]));
  for (std::size_t i = 0; i < WIDTH; ++i)
    s[i] = gl::add(gl::mul(F(detail::kInternalDiag[i]), F(s[i])), sum).v;
}

void full_round(State& s, std::size_t r) {
  for (std::size_t i = 0; i < WIDTH; ++i)
    s[i] = sbox7(gl::add(F(s[i]), F(detail::kRoundFull[WIDTH * r + i]))).v;
  external(s);
}

// Seven little-endian bytes per element: always below p, so no reduction is needed.
void bytes_to_rate(const std::uint8_t* block, std::uint64_t out[RATE]) {
  for (std::size_t i = 0; i < RATE; ++i) {
    std::uint64_t v = 0;
    for (std::size_t b = 0; b < 7; ++b) v |= static_cast<std::uint64_t>(block[7 * i + b]) << (8 * b);
    out[i] = v;
  }
}

Digest digest_of(const State& s) {
  Digest d{};
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t b = 0; b < 8; ++b) d[8 * i + b] = static_cast<std::uint8_t>(s[i] >> (8 * b));
  return d;
}

// A digest back to four elements; digests are canonical, and any 64-bit word is reduced so
// that keys of arbitrary bytes stay well defined.
void digest_words(const Digest& d, std::uint64_t out[4]) {
  for (std::size_t i = 0; i < 4; ++i) {
    std::uint64_t v = 0;
    for (std::size_t b = 0; b < 8; ++b) v |= static_cast<std::uint64_t>(d[8 * i + b]) << (8 * b);
    out[i] = F(v).v;
  }
}

}  // namespace

void permute(State& s) {
  external(s);
  for (std::size_t r = 0; r < 4; ++r) full_round(s, r);
  for (std::size_t r = 0; r < 16; ++r) {
    s[0] = gl::pow_p_minus_2(gl::add(F(s[0]), F(detail::kRoundPartial[r]))).v;
    internal(s);
  }
  for (std::size_t r = 4; r < 8; ++r) full_round(s, r);
}

Hasher::Hasher() : Hasher(DOMAIN_HASH) {}

Hasher::Hasher(std::uint64_t domain) { state_[CAP_DOMAIN] = domain; }

Hasher Hasher::keyed(const Digest& key) {
  Hasher h(DOMAIN_KEYED);
  h.update(std::span<const std::uint8_t>(key));
  return h;
}

Hasher Hasher::derive_key_context() { return Hasher(DOMAIN_DERIVE_CONTEXT); }

Hasher Hasher::derive_key_material(const Digest& context_hash) {
  Hasher h(DOMAIN_DERIVE_MATERIAL);
  std::uint64_t w[4];
  digest_words(context_hash, w);
  for (std::size_t i = 0; i < 4; ++i) h.state_[i] = w[i];
  permute(h.state_);
  return h;
}

void Hasher::absorb_block(const std::uint8_t* block) {
  std::uint64_t e[RATE];
  bytes_to_rate(block, e);
  for (std::size_t i = 0; i < RATE; ++i) state_[i] = gl::add(F(state_[i]), F(e[i])).v;
  permute(state_);
}

Hasher& Hasher::update(std::span<const std::uint8_t> data) {
  absorbed_ += data.size();
  std::size_t pos = 0;
  if (buf_len_ > 0) {
    const std::size_t take = std::min(RATE_BYTES - buf_len_, data.size());
    std::memcpy(buf_.data() + buf_len_, data.data(), take);
    buf_len_ += take;
    pos = take;
    if (buf_len_ < RATE_BYTES) return *this;
    absorb_block(buf_.data());
    buf_len_ = 0;
  }
  while (data.size() - pos >= RATE_BYTES) {
    absorb_block(data.data() + pos);
    pos += RATE_BYTES;
  }
  buf_len_ = data.size() - pos;
  if (buf_len_ > 0) std::memcpy(buf_.data(), data.data() + pos, buf_len_);
  return *this;
}

Digest Hasher::finalize() const {
  // Always one padded block: the rest of the input, 0x01, zeros; the byte length goes to the
  // capacity so that inputs differing only in trailing zeros cannot collide.
  State s = state_;
  std::array<std::uint8_t, RATE_BYTES> pad{};
  std::memcpy(pad.data(), buf_.data(), buf_len_);
  pad[buf_len_] = 0x01;
  std::uint64_t e[RATE];
  bytes_to_rate(pad.data(), e);
  for (std::size_t i = 0; i < RATE; ++i) s[i] = gl::add(F(s[i]), F(e[i])).v;
  s[CAP_LENGTH] = F(absorbed_).v;
  permute(s);
  return digest_of(s);
}

Digest hash(std::span<const std::uint8_t> data) { return Hasher().update(data).finalize(); }

Digest keyed_hash(const Digest& key, std::span<const std::uint8_t> data) {
  return Hasher::keyed(key).update(data).finalize();
}

Digest derive_key(std::string_view context, std::span<const std::uint8_t> material) {
  const Digest ctx = Hasher::derive_key_context().update(context).finalize();
  return Hasher::derive_key_material(ctx).update(material).finalize();
}

Digest hash_leaf(std::span<const std::uint8_t> chunk, std::uint64_t counter, bool is_root) {
  // Content first through the plain sponge, then one permutation binds position and flags.
  const Digest base = hash(chunk);
  State s{};
  digest_words(base, s.data());
  s[CAP_COUNTER] = F(counter).v;
  s[CAP_FLAGS] = FLAG_CHUNK | (is_root ? FLAG_ROOT : 0);
  permute(s);
  return digest_of(s);
}

Digest hash_node(const Digest& left, const Digest& right, bool is_root) {
  // Two 4-element children fill the 8-element rate exactly: one permutation.
  State s{};
  digest_words(left, s.data());
  digest_words(right, s.data() + 4);
  s[CAP_FLAGS] = FLAG_PARENT | (is_root ? FLAG_ROOT : 0);
  permute(s);
  return digest_of(s);
}

namespace detail {

Digest merge_leaves(std::span<const Digest> leaves, bool is_root) {
  if (leaves.size() == 1) return leaves[0];
  // Left subtree: the largest power of two strictly below the leaf count.
  std::size_t split = 1;
  while (split * 2 < leaves.size()) split *= 2;
  const Digest l = merge_leaves(leaves.subspan(0, split), false);
  const Digest r = merge_leaves(leaves.subspan(split), false);
  return hash_node(l, r, is_root);
}

void parallel_for(std::size_t n, const void* ctx, void (*body)(const void*, std::size_t)) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) body(ctx, i);
  });
}

}  // namespace detail

Digest root_hash(std::span<const std::uint8_t> data, bool parallel) {
  return root_hash_chunks(
      data.size(),
      [&](std::uint64_t i, std::span<std::uint8_t> out) {
        const std::size_t off = static_cast<std::size_t>(i) * CHUNK_BYTES;
        const std::size_t len = std::min(CHUNK_BYTES, data.size() - off);
        std::memcpy(out.data(), data.data() + off, len);
        return len;
      },
      parallel);
}

std::string to_hex(std::span<const std::uint8_t> bytes) {
  static constexpr char digits[] = "0123456789abcdef";
  std::string s(bytes.size() * 2, '0');
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    s[2 * i] = digits[bytes[i] >> 4];
    s[2 * i + 1] = digits[bytes[i] & 15];
  }
  return s;
}

bool from_hex(std::string_view hex, Digest& out) {
  if (hex.size() != 2 * DIGEST_BYTES) return false;
  auto nib = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  for (std::size_t i = 0; i < DIGEST_BYTES; ++i) {
    const int hi = nib(hex[2 * i]), lo = nib(hex[2 * i + 1]);
    if (hi < 0 || lo < 0) return false;
    out[i] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  return true;
}

}  // namespace r1::hemera
