// Fuzz the titles and crystal side-file readers (R1-TEST-010) against a fixed small snapshot.
#include "fuzz_target.hpp"
#include "readers.hpp"

R1_FUZZ_TARGET(side_files) {
  if (size == 0) return 0;
  static const r1::Snapshot base = [] {
    auto s = r1::detail::read_edge_list("a\tb\nb\tc\nc\td\n", "base", false, {});
    return std::move(s).value();
  }();
  r1::Snapshot s = base;
  const auto kind = (data[0] & 1) ? r1::detail::SideKind::kCrystal : r1::detail::SideKind::kTitles;
  const bool strict = (data[0] & 2) != 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  const auto st = r1::detail::apply_side_text(s, text, "fuzz", kind, strict, 1, nullptr);
  if (!st.is_ok()) return 0;
  if (kind == r1::detail::SideKind::kTitles) {
    R1_FUZZ_CHECK(s.titles.size() == s.particles.size());
    // Titles survive their section format.
    r1::Snapshot t = base;
    R1_FUZZ_CHECK(r1::detail::apply_side_text(t, r1::detail::format_titles_section(s), "section",
                                              r1::detail::SideKind::kTitles, true, 1, nullptr)
                      .is_ok());
    for (std::size_t i = 0; i < s.titles.size(); ++i)
      R1_FUZZ_CHECK(t.titles[i] == s.titles[i]);
  } else {
    R1_FUZZ_CHECK(s.crystal.size() == s.particles.size());
  }
  return 0;
}
