// Goldilocks field against Boost.Multiprecision cpp_int (R1-NUM-020..023).
#include "r1/fixedpoint/goldilocks.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <boost/multiprecision/cpp_int.hpp>

namespace {

using boost::multiprecision::cpp_int;
using r1::gl::Fp;

const cpp_int kP = cpp_int(r1::gl::P);

cpp_int big(Fp a) { return cpp_int(a.v); }
std::uint64_t small(const cpp_int& x) { return static_cast<std::uint64_t>(x); }

// Values near 0, near p and near 2^64 matter most for carries; mix them in.
rc::Gen<std::uint64_t> edgy_u64() {
  return rc::gen::oneOf(
      rc::gen::arbitrary<std::uint64_t>(),
      rc::gen::map(rc::gen::inRange<std::uint64_t>(0, 1u << 20), [](std::uint64_t d) { return d; }),
      rc::gen::map(rc::gen::inRange<std::uint64_t>(0, 1u << 20), [](std::uint64_t d) { return r1::gl::P - 1 - d; }),
      rc::gen::map(rc::gen::inRange<std::uint64_t>(0, 1u << 20), [](std::uint64_t d) { return ~std::uint64_t{0} - d; }),
      rc::gen::map(rc::gen::inRange<std::uint64_t>(0, 1u << 20), [](std::uint64_t d) { return (std::uint64_t{1} << 32) + d - (1u << 19); }));
}

rc::Gen<Fp> field() { return rc::gen::map(edgy_u64(), [](std::uint64_t x) { return Fp::from_u64(x); }); }

RC_GTEST_PROP(Goldilocks, FromU64IsCanonicalResidue, ()) {
  const std::uint64_t x = *edgy_u64();
  RC_ASSERT(Fp::from_u64(x).v == small(cpp_int(x) % kP));
}

RC_GTEST_PROP(Goldilocks, AddSubMulMatchCppInt, ()) {
  const Fp a = *field(), b = *field();
  RC_ASSERT(r1::gl::add(a, b).v == small((big(a) + big(b)) % kP));
  RC_ASSERT(r1::gl::sub(a, b).v == small((big(a) - big(b) + kP) % kP));
  RC_ASSERT(r1::gl::mul(a, b).v == small((big(a) * big(b)) % kP));
}

RC_GTEST_PROP(Goldilocks, Reduce128MatchesCppInt, (std::uint64_t hi, std::uint64_t lo)) {
  const r1::u128 x = (static_cast<r1::u128>(hi) << 64) | lo;
  const cpp_int bx = (cpp_int(hi) << 64) | cpp_int(lo);
  RC_ASSERT(r1::gl::reduce128(x).v == small(bx % kP));
}

RC_GTEST_PROP(Goldilocks, PowMatchesCppInt, ()) {
  const Fp a = *field();
  const std::uint64_t e = *rc::gen::arbitrary<std::uint64_t>();
  RC_ASSERT(r1::gl::pow(a, e).v == small(boost::multiprecision::powm(big(a), cpp_int(e), kP)));
}

RC_GTEST_PROP(Goldilocks, InverseTimesSelfIsOne, ()) {
  const Fp a = *field();
  const auto inv = r1::gl::inverse(a);
  if (a.v == 0) {
    RC_ASSERT(!inv.has_value());
    RC_ASSERT(r1::gl::pow_p_minus_2(a).v == 0u);
  } else {
    RC_ASSERT(inv.has_value());
    RC_ASSERT(r1::gl::mul(a, *inv).v == 1u);
    RC_ASSERT(inv->v == r1::gl::pow(a, r1::gl::P - 2).v);
  }
}

RC_GTEST_PROP(Goldilocks, EncodingRoundTripsAndNegates, ()) {
  const std::int64_t r = *rc::gen::inRange<std::int64_t>(-r1::gl::ENCODE_MAX, r1::gl::ENCODE_MAX);
  const auto e = r1::gl::encode(r);
  RC_ASSERT(e.has_value());
  RC_ASSERT(r1::gl::decode(*e) == r);
  // The encoding is a ring map on its range: encode(-r) = -encode(r).
  RC_ASSERT(r1::gl::encode(-r)->v == r1::gl::neg(*e).v);
}

TEST(Goldilocks, EncodingRejectsOutOfRange) {
  EXPECT_FALSE(r1::gl::encode(r1::gl::ENCODE_MAX + 1).has_value());
  EXPECT_FALSE(r1::gl::encode(-r1::gl::ENCODE_MAX - 1).has_value());
  EXPECT_FALSE(r1::gl::encode(INT64_MIN).has_value());
  EXPECT_EQ(r1::gl::encode(-1)->v, r1::gl::P - 1);
  EXPECT_EQ(r1::gl::decode(Fp::from_u64(r1::gl::P - 1)), -1);
}

TEST(Goldilocks, KnownValues) {
  // 2^64 = 2^32 - 1 and 2^96 = -1 (mod p).
  const Fp two = Fp::from_u64(2);
  EXPECT_EQ(r1::gl::pow(two, 64).v, 0xFFFFFFFFull);
  EXPECT_EQ(r1::gl::pow(two, 96).v, r1::gl::P - 1);
  EXPECT_EQ(r1::gl::pow(two, 192).v, 1u);
}

}  // namespace
