#!/usr/bin/env python3
"""Prints the fixed-point constants of fixedpoint/elementary.cpp (R1-NUM-040..049).

Every constant is round-to-nearest of the real value times a power of two, computed with mpmath at
400 bits, far beyond the 120 fractional bits the C++ side keeps. The test
ElementaryConstants.* in fixedpoint/elementary_test.cpp re-derives each one with
boost::multiprecision::cpp_bin_float_100, so this script is a convenience, not a trusted source.
"""
import mpmath

mpmath.mp.prec = 400
F = 120          # fractional bits of the internal fixed-point format W
ATAN_STEPS = 44  # CORDIC iterations of atan2 (see proofs/elementary_error.md)


def rnd(x, bits):
    return int(mpmath.nint(x * mpmath.mpf(2) ** bits))


def w(v):
    assert 0 <= v < 2 ** 127
    return "w(0x%016x, 0x%016x)" % (v >> 64, v & (2 ** 64 - 1))


pio2 = mpmath.pi / 2
pio2_scaled = pio2 * mpmath.mpf(2) ** F
pio2_hi = int(mpmath.floor(pio2_scaled))
pio2_lo = rnd(pio2_scaled - pio2_hi, 64)

print("constexpr u128 kLn2 = %s;" % w(rnd(mpmath.log(2), F)))
print("constexpr u128 kLog2e = %s;" % w(rnd(1 / mpmath.log(2), F)))
print("constexpr u128 kPi = %s;" % w(rnd(mpmath.pi, F)))
print("constexpr u128 kHalfPiHi = %s;" % w(pio2_hi))
print("constexpr std::uint64_t kHalfPiLo = 0x%016x;" % pio2_lo)
print("constexpr std::uint64_t kTwoOverPi64 = 0x%016x;" % rnd(2 / mpmath.pi, 64))
print("constexpr std::array<u128, %d> kAtanPow2 = {" % ATAN_STEPS)
for i in range(ATAN_STEPS):
    print("    %s," % w(rnd(mpmath.atan(mpmath.mpf(2) ** -i), F)))
print("};")
for name, val in [("pi", mpmath.pi), ("half_pi", mpmath.pi / 2), ("two_pi", 2 * mpmath.pi),
                  ("ln2", mpmath.log(2)), ("e", mpmath.e)]:
    print("// %s: raw %d = 0x%x" % (name, rnd(val, 32), rnd(val, 32)))
