// Fuzz the custom overlay reader (R1-ENC-040..043, R1-TEST-010): whatever it accepts writes back as
// canonical TOML that reads to the same overlay, and every style it yields is in range.
#include "fuzz_target.hpp"
#include "r1/reference/encoding.hpp"

R1_FUZZ_TARGET(overlay) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto o = r1::parse_custom_overlay(text, "fuzz.toml");
  if (!o.is_ok()) {
    R1_FUZZ_CHECK(o.status().kind() == r1::ErrorKind::kInput);
    R1_FUZZ_CHECK(o.status().message().find('\n') == std::string::npos);
    return 0;
  }
  const std::string canonical = r1::custom_overlay_text(*o);
  auto back = r1::parse_custom_overlay(canonical, "canonical.toml");
  R1_FUZZ_CHECK(back.is_ok());
  R1_FUZZ_CHECK(*back == *o);
  R1_FUZZ_CHECK(r1::custom_overlay_text(*back) == canonical);
  const r1::Q32 max_size = r1::Q32::from_int(r1::kMaxSizeMultiplier);
  for (std::uint8_t t = 0; t < 7; ++t) {
    const r1::CrystalTag tag{t < 6 ? t : r1::CrystalTag::kUnknown, static_cast<std::uint8_t>(t * 3), static_cast<std::uint8_t>(t % 5)};
    const auto st = r1::overlay_style(*o, tag, o->particles.empty() ? nullptr : &o->particles.front().style);
    if (st.size) R1_FUZZ_CHECK(st.size->raw > 0 && *st.size <= max_size);
    if (st.shape) R1_FUZZ_CHECK(static_cast<std::size_t>(*st.shape) < r1::kShapeNames.size());
  }
  return 0;
}
