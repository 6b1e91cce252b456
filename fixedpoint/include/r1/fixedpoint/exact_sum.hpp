// Exact accumulation of Q32 sums and dot products, rounded once (R1-NUM-030..034).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>

#include "r1/fixedpoint/int128.hpp"
#include "r1/fixedpoint/q32.hpp"

namespace r1::fx {

// A 192-bit two's complement integer counting units of 2^-64: the exact scale of a product of
// two Q32 raws, and of a plain Q32 value shifted up by 32 bits. Addition is modulo 2^192, so the
// limbs after any sequence of adds and merges are the same whatever their order; they equal the
// true sum whenever that sum lies in [-2^191, 2^191), which holds for any 2^65 - 1 products
// (proofs/accumulator_width.md). round() is the only rounding (R1-NUM-033).
class ExactSum {
 public:
  constexpr ExactSum() noexcept = default;

  // The inner loop of every dot product: one 64x64->128 multiply and a three-limb add.
  constexpr void add_product(Q32 a, Q32 b) noexcept { add_term(static_cast<i128>(a.raw) * b.raw); }
  // -(a*b) fits too: |a*b| <= 2^126.
  constexpr void sub_product(Q32 a, Q32 b) noexcept { add_term(-(static_cast<i128>(a.raw) * b.raw)); }
  constexpr void add(Q32 a) noexcept { add_term(static_cast<i128>(a.raw) * Q32::kOneRaw); }
  constexpr void sub(Q32 a) noexcept { add_term(-(static_cast<i128>(a.raw) * Q32::kOneRaw)); }
  // A term already on the 2^-64 scale (|t| < 2^127).
  constexpr void add_term(i128 t) noexcept {
    const u128 u = static_cast<u128>(t);
    lo_ += u;
    // Carry out of the low 128 bits, plus the sign extension of t into the high limb.
    hi_ += static_cast<std::uint64_t>(lo_ < u) + (t < 0 ? ~std::uint64_t{0} : 0);
  }

  // Adds another partial sum exactly (R1-NUM-032): parallel workers merge in any grouping.
  constexpr void merge(const ExactSum& o) noexcept {
    lo_ += o.lo_;
    hi_ += o.hi_ + static_cast<std::uint64_t>(lo_ < o.lo_);
  }
  constexpr ExactSum& operator+=(const ExactSum& o) noexcept {
    merge(o);
    return *this;
  }

  // The sum rounded once to Q32, ties-to-even; std::nullopt when it is out of range.
  constexpr std::optional<Q32> checked_round() const noexcept {
    // floor(V / 2^32) as (q_hi:q_lo) = bits 32..191 of V, sign-extended; rem = bits 0..31.
    u128 q_lo = (lo_ >> 32) | (static_cast<u128>(hi_) << 96);
    std::int64_t q_hi = static_cast<std::int64_t>(hi_) >> 32;
    const auto rem = static_cast<std::uint32_t>(lo_);
    constexpr std::uint32_t kHalf = std::uint32_t{1} << 31;
    if (rem > kHalf || (rem == kHalf && (q_lo & 1) != 0)) {
      if (++q_lo == 0) ++q_hi;
    }
    // In int64 range iff the 160-bit quotient is the sign extension of its low 64 bits.
    const bool fits = (q_hi == 0 && q_lo <= static_cast<u128>(INT64_MAX)) ||
                      (q_hi == -1 && q_lo >= (u128_max << 63));
    if (!fits) return std::nullopt;
    return Q32{static_cast<std::int64_t>(static_cast<std::uint64_t>(q_lo))};
  }
  // Throws OverflowError when the rounded sum is out of range.
  constexpr Q32 round() const {
    const auto r = checked_round();
    if (!r) detail::throw_overflow("ExactSum::round");
    return *r;
  }

  // -1, 0 or 1: the sign of the exact sum.
  constexpr int signum() const noexcept {
    if (static_cast<std::int64_t>(hi_) < 0) return -1;
    return (hi_ != 0 || lo_ != 0) ? 1 : 0;
  }

  // The three 64-bit limbs of the two's complement value, least significant first: the exact
  // state, for serialisation and for tests.
  constexpr std::array<std::uint64_t, 3> limbs() const noexcept {
    return {static_cast<std::uint64_t>(lo_), static_cast<std::uint64_t>(lo_ >> 64), hi_};
  }
  static constexpr ExactSum from_limbs(const std::array<std::uint64_t, 3>& l) noexcept {
    ExactSum s;
    s.lo_ = (static_cast<u128>(l[1]) << 64) | l[0];
    s.hi_ = l[2];
    return s;
  }

  friend constexpr bool operator==(const ExactSum&, const ExactSum&) noexcept = default;

 private:
  u128 lo_ = 0;            // bits 0..127
  std::uint64_t hi_ = 0;   // bits 128..191; bit 191 is the sign
};

// sum_i a_i * b_i rounded once (R1-NUM-031). Throws std::invalid_argument when the lengths
// differ and OverflowError when the rounded result is out of range.
Q32 exact_dot(std::span<const Q32> a, std::span<const Q32> b);
// sum_i x_i rounded once (it is exact unless it overflows).
Q32 exact_sum(std::span<const Q32> x);

}  // namespace r1::fx
