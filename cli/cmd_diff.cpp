// r1 diff A B [--heatmap OUT.png] [--threshold T] [--fail-mean M] [--warn-max W] [--json]: a
// perceptual image comparison with a verdict exit status (spec/render.md R1-RND-112..116,
// spec/errors.md R1-ERR-005).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "render/image_diff.hpp"

namespace r1::cli {

namespace {

namespace fs = std::filesystem;

struct DiffCliOptions {
  std::string a, b, heatmap;
  render::DiffOptions diff;
  bool json = false;
};

// A bound must be a number >= 0 (warn_max may be infinite: no hard ceiling).
Status check_bound(const char* name, double v, bool allow_infinite) {
  if (std::isnan(v) || v < 0 || (!allow_infinite && std::isinf(v)))
    return Status::input(std::string("diff: ") + name + " must be a number >= 0");
  return Status::ok();
}

// The heatmap's ramp saturates (white) at three times the threshold, so the threshold itself is
// pure red; with threshold 0 it saturates at 1 (about a just-noticeable difference) instead of
// at 0, where every difference would be white and the map would show no gradation.
double heatmap_scale(double threshold) { return std::max(3.0 * threshold, 1.0); }

double percent(std::uint64_t part, std::uint64_t whole) {
  return whole == 0 ? 0.0 : 100.0 * static_cast<double>(part) / static_cast<double>(whole);
}

// warn_max in JSON: null when off (JSON has no infinity).
nlohmann::json bound_json(double v) { return std::isinf(v) ? nlohmann::json(nullptr) : nlohmann::json(v); }

Status report_size_mismatch(const DiffCliOptions& o, int wa, int ha, int wb, int hb) {
  const render::Verdict v = render::Verdict::kSizeMismatch;
  if (o.json) {
    const nlohmann::json j = {{"a", o.a},
                              {"b", o.b},
                              {"a_size", {wa, ha}},
                              {"b_size", {wb, hb}},
                              {"verdict", render::verdict_name(v)},
                              {"exit", static_cast<int>(v)}};
    std::cout << j.dump(2) << "\n";
  } else {
    std::printf("A: %s  %dx%d\n", o.a.c_str(), wa, ha);
    std::printf("B: %s  %dx%d\n", o.b.c_str(), wb, hb);
    std::printf("%s: the images differ in size\n", render::verdict_name(v));
  }
  verdict_exit() = static_cast<int>(v);
  return Status::ok();
}

Status run_diff(const DiffCliOptions& o) {
  R1_TRY(check_bound("--threshold", o.diff.threshold, false));
  R1_TRY(check_bound("--fail-mean", o.diff.fail_mean, false));
  R1_TRY(check_bound("--warn-max", o.diff.warn_max, true));
  // Checked before any work: a misnamed heatmap is an input error, not a late output failure.
  std::string ext = fs::path(o.heatmap).extension().string();
  for (char& c : ext) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  if (!o.heatmap.empty() && ext != ".png")
    return Status::input(o.heatmap + ": the heatmap is a PNG (name it .png)");

  int wa = 0, ha = 0, wb = 0, hb = 0;
  R1_ASSIGN(const std::vector<std::uint8_t> a, render::read_srgb8(o.a, &wa, &ha));
  R1_ASSIGN(const std::vector<std::uint8_t> b, render::read_srgb8(o.b, &wb, &hb));
  if (wa != wb || ha != hb) return report_size_mismatch(o, wa, ha, wb, hb);

  std::vector<float> heat;
  const render::DiffStats st = render::diff_srgb8(a, b, wa, ha, o.diff, &heat);
  // Over the pixels either image covers (not the default background), R1-RND-117.
  const render::CoveredMean covered = render::covered_mean_2000(a, b, heat, render::View{}.background);
  // The heatmap is written before anything is printed: a failed write is one error line and
  // nothing else (R1-ERR-001, R1-ERR-003).
  if (!o.heatmap.empty()) R1_TRY(render::write_heatmap(heat, wa, ha, heatmap_scale(o.diff.threshold), o.heatmap));
  const render::Verdict v = render::judge(st, o.diff);

  if (o.json) {
    const nlohmann::json j = {{"a", o.a},
                              {"b", o.b},
                              {"width", st.width},
                              {"height", st.height},
                              {"pixels", st.pixels},
                              {"mean_2000", st.mean_2000},
                              {"p95_2000", st.p95_2000},
                              {"p99_2000", st.p99_2000},
                              {"max_2000", st.max_2000},
                              {"max_x", st.max_x},
                              {"max_y", st.max_y},
                              {"mean_76", st.mean_76},
                              {"p99_76", st.p99_76},
                              {"max_76", st.max_76},
                              {"over", st.over},
                              {"covered", covered.covered},
                              {"covered_mean_2000", covered.mean_2000},
                              {"over_percent", percent(st.over, st.pixels)},
                              {"threshold", o.diff.threshold},
                              {"fail_mean", o.diff.fail_mean},
                              {"warn_max", bound_json(o.diff.warn_max)},
                              {"heatmap", o.heatmap.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.heatmap)},
                              {"verdict", render::verdict_name(v)},
                              {"exit", static_cast<int>(v)}};
    std::cout << j.dump(2) << "\n";
  } else {
    std::printf("A: %s\nB: %s\n", o.a.c_str(), o.b.c_str());
    std::printf("size        %dx%d, %llu pixels\n", st.width, st.height, static_cast<unsigned long long>(st.pixels));
    std::printf("DE2000      mean %.4f  p95 %.4f  p99 %.4f  max %.4f at (%d, %d)\n", st.mean_2000, st.p95_2000,
                st.p99_2000, st.max_2000, st.max_x, st.max_y);
    std::printf("DE76        mean %.4f  p99 %.4f  max %.4f\n", st.mean_76, st.p99_76, st.max_76);
    std::printf("over        %llu pixels (%.3f%%) above DE2000 %g\n", static_cast<unsigned long long>(st.over),
                percent(st.over, st.pixels), o.diff.threshold);
    if (!o.heatmap.empty())
      std::printf("heatmap     %s (white at DE2000 >= %g)\n", o.heatmap.c_str(), heatmap_scale(o.diff.threshold));
    char why[160];
    if (v == render::Verdict::kPass)
      std::snprintf(why, sizeof why, "mean %.4f <= %g, no pixel above %g", st.mean_2000, o.diff.fail_mean, o.diff.threshold);
    else if (v == render::Verdict::kWarn)
      std::snprintf(why, sizeof why, "mean %.4f <= %g, but %llu pixels above %g", st.mean_2000, o.diff.fail_mean,
                    static_cast<unsigned long long>(st.over), o.diff.threshold);
    else if (st.mean_2000 > o.diff.fail_mean)
      std::snprintf(why, sizeof why, "mean %.4f > %g (--fail-mean)", st.mean_2000, o.diff.fail_mean);
    else
      std::snprintf(why, sizeof why, "max %.4f > %g (--warn-max)", st.max_2000, o.diff.warn_max);
    std::printf("%s: %s\n", render::verdict_name(v), why);
  }
  verdict_exit() = static_cast<int>(v);
  return Status::ok();
}

}  // namespace

void add_diff(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<DiffCliOptions>();
  auto* cmd = app.add_subcommand("diff", "compare two images perceptually (CIEDE2000); exit 0 pass, 1 warn, 4 fail, 5 sizes differ");
  cmd->add_option("A", o->a, "first image: .png (8-bit RGB/RGBA) or .exr (scene-linear, as r1 render writes)")->required();
  cmd->add_option("B", o->b, "second image, the same size")->required();
  cmd->add_option("--heatmap", o->heatmap, "write the per-pixel CIEDE2000 as a PNG (black 0, red at the threshold, white at 3x)");
  cmd->add_option("--threshold", o->diff.threshold, "per-pixel CIEDE2000 above which a pixel counts as over (2)");
  cmd->add_option("--fail-mean", o->diff.fail_mean, "fail when the mean CIEDE2000 exceeds this (2)");
  cmd->add_option("--warn-max", o->diff.warn_max, "fail when any pixel's CIEDE2000 exceeds this (off)");
  cmd->add_flag("--json", o->json, "print one JSON object");
  cmd->callback([o, &selected] { selected = [o] { return run_diff(*o); }; });
}

}  // namespace r1::cli
