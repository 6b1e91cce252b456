// r1 render EPOCH_DIR [--view FILE | --orbit K | --eye X Y Z --target X Y Z] [--backend NAME]
// -o OUT.png|OUT.exr: the chosen backend's frame stage (spec/render.md R1-RND-090..094, R1-BKD-016).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "backend_option.hpp"
#include "commands.hpp"
#include "image_size.hpp"
#include "progress.hpp"
#include "r1/reference/atomic_file.hpp"
#include "r1/reference/epoch_io.hpp"
#include "r1/reference/input_file.hpp"
#include "render/legibility.hpp"
#include "render/navigation.hpp"
#include "render/content_pass.hpp"
#include "render/neural_field.hpp"
#include "render/renderer.hpp"
#include "timing.hpp"

namespace r1::cli {

namespace {

namespace fs = std::filesystem;

struct RenderCliOptions {
  std::string dir, out, view_file, size, write_view;
  int orbit = 0;
  std::vector<double> eye, target, up;
  double fov = 0, time = 0, distance = 0;
  bool no_edges = false, no_labels = false, no_field = false, quiet = false, legibility = false;
  std::string field = "auto", field_file, march = "skipping";
  std::string path, write_path;  // R1-VIEW-050: a camera path (warp:QUERY, follow:SECONDS) and its poses
  double fps = 30;
  BackendOption backend;
};

struct TrainFieldOptions {
  std::string dir, out;
  render::NeuralConfig config;
  std::string block = "none";
  bool quiet = false;
};

// The trained field's default place: beside the epoch's files (R1-NRF-030).
std::string field_path(const std::string& dir, const std::string& given) {
  return given.empty() ? (fs::path(dir) / "field.nrf").string() : given;
}

Status run_train_field(const TrainFieldOptions& o) {
  ProgressLine progress;
  const auto t0 = std::chrono::steady_clock::now();
  R1_ASSIGN(const Epoch e, read_epoch(o.dir));
  if (e.ids.empty()) return Status::input(o.dir + ": the epoch has no particles");
  const render::Scene scene = render::make_scene(e);
  const auto t1 = std::chrono::steady_clock::now();
  render::NeuralConfig config = o.config;
  config.block = o.block == "clifford" ? config.hidden / 2 : 0;
  R1_ASSIGN(const render::NeuralField f,
            render::train_neural_field(scene, config, render::neural_seed(e.snapshot_digest), progress.sink()));
  const double train_s = seconds_since(t1);
  progress.finish();
  const std::string bytes = render::encode_neural_field(f, e.snapshot_digest);
  // Into the epoch directory it is listed in the manifest like the epoch's own files (R1-NRF-030).
  const std::string path = field_path(o.dir, o.out);
  if (o.out.empty()) {
    R1_TRY(add_epoch_file(o.dir, "field.nrf", bytes));
  } else {
    R1_TRY(write_file_atomic(path, bytes));
  }
  if (!o.quiet)
    std::printf("%s: neural field, %u levels x 2^%u entries, %u hidden%s, %zu bytes; %u steps of %u over %u samples in %.2f s "
                "(loss %.4g -> %.4g); %.2f s in all\n",
                path.c_str(), f.config.levels, f.config.log2_table, f.config.hidden, f.config.block > 0 ? " with the Clifford block" : "", bytes.size(), f.config.steps,
                f.config.batch, f.config.samples, train_s, f.loss_first, f.loss_last, seconds_since(t0));
  return Status::ok();
}

// OUT for one view; OUT-000.EXT, OUT-001.EXT ... for an orbit (R1-RND-091).
fs::path frame_path(const fs::path& out, int k, int count) {
  if (count <= 1) return out;
  char index[16];
  std::snprintf(index, sizeof index, "-%03d", k);
  return out.parent_path() / (out.stem().string() + index + out.extension().string());
}

void print_stats(const fs::path& path, const render::View& v, const render::FrameStats& st) {
  std::printf("%s  %dx%d  visible %llu (T0 %llu, T1 %llu, T2 %llu, T3 %llu, Tinf %llu), edges %llu of %llu (%llu in view), splats %llu, labels %llu\n",
              path.string().c_str(), v.width, v.height, static_cast<unsigned long long>(st.visible),
              static_cast<unsigned long long>(st.tier_count[0]), static_cast<unsigned long long>(st.tier_count[1]),
              static_cast<unsigned long long>(st.tier_count[2]), static_cast<unsigned long long>(st.tier_count[3]),
              static_cast<unsigned long long>(st.tier_count[4]), static_cast<unsigned long long>(st.edges_drawn),
              static_cast<unsigned long long>(st.edges_considered), static_cast<unsigned long long>(st.edges_in_view),
              static_cast<unsigned long long>(st.splats),
              static_cast<unsigned long long>(st.labels));
  std::printf("  time %.2f s: cull %.3f, T1/T2 impostors %.2f, edges %.2f, T3 splats %.2f, Tinf field %.2f, labels %.3f\n", st.total_s,
              st.cull_s, st.impostor_s, st.edge_s, st.splat_s, st.field_s, st.label_s);
  if (st.content > 0) std::printf("  T0 content: %llu particle%s opened\n", static_cast<unsigned long long>(st.content), st.content == 1 ? "" : "s");
  if (st.field_rewalked > 0)
    std::printf("  the backend's field pass walked the hierarchy again at each sample for %llu rays past its candidate cap\n",
                static_cast<unsigned long long>(st.field_rewalked));
  if (st.host_pixels > 0)
    std::printf("  the backend's field pass left %llu pixels (%.2f%%) to the host\n", static_cast<unsigned long long>(st.host_pixels),
                100.0 * static_cast<double>(st.host_pixels) / (static_cast<double>(v.width) * v.height));
  if (st.field_candidates > 0) {
    const double pixels = static_cast<double>(v.width) * v.height;
    std::printf("  field per pixel: %.1f nodes tested, %.1f on the ray, %.1f samples, %.0f kernel evaluations\n",
                static_cast<double>(st.field_walked) / pixels, static_cast<double>(st.field_candidates) / pixels,
                static_cast<double>(st.field_samples) / pixels,
                static_cast<double>(st.field_evaluations) / pixels);
  }
}

// R1-VIEW-050: the views of a camera path from `start`, one every 1/fps seconds and one at its end:
// warp:QUERY (R1-VIEW-021, 0.5 s) or follow:SECONDS (R1-VIEW-032 with no user velocity).
Result<std::vector<render::View>> path_views(const RenderCliOptions& c, const Epoch& e, const render::Scene& scene,
                                             const render::View& start) {
  if (!(c.fps > 0 && c.fps <= 1000)) return Status::input("render: --fps must lie in (0, 1000]");
  const auto colon = c.path.find(':');
  const std::string kind = c.path.substr(0, colon), arg = colon == std::string::npos ? "" : c.path.substr(colon + 1);
  std::vector<render::View> views;
  const double dt = 1.0 / c.fps;
  if (kind == "warp") {
    R1_ASSIGN(const std::uint32_t p, render::find_particle(e.ids, e.titles, scene.phi, arg));
    const render::Camera to = render::warp_end(start.camera, scene, p);
    const auto steps = static_cast<int>(std::ceil(render::kWarpSeconds * c.fps - 1e-9));
    for (int k = 0; k <= steps; ++k) {
      render::View v = start;
      v.camera = render::warp_at(start.camera, to, std::min(k * dt, render::kWarpSeconds));
      views.push_back(v);
    }
    return views;
  }
  if (kind == "follow") {
    double seconds = 0;
    const auto r = std::from_chars(arg.data(), arg.data() + arg.size(), seconds);
    if (r.ec != std::errc() || r.ptr != arg.data() + arg.size() || !(seconds > 0 && seconds <= 600))
      return Status::input("render: --path follow:SECONDS needs 0 < SECONDS <= 600");
    const render::EdgeIndex index = render::index_edges(scene);
    const auto steps = static_cast<int>(std::ceil(seconds * c.fps - 1e-9));
    render::View v = start;
    views.push_back(v);
    for (int k = 0; k < steps; ++k) {
      v.camera = render::follow_flow_step(scene, index, v.camera, {0, 0, 0}, dt);
      views.push_back(v);
    }
    return views;
  }
  return Status::input("render: --path must be warp:QUERY or follow:SECONDS (got '" + c.path + "')");
}

// The poses of a path as JSON: [{"t": s, "position": [x, y, z], "orientation": [w, x, y, z], "fov": deg}, ...].
std::string path_json(const std::vector<render::View>& views, double fps) {
  nlohmann::json a = nlohmann::json::array();
  for (std::size_t k = 0; k < views.size(); ++k) {
    const auto& cam = views[k].camera;
    a.push_back({{"t", static_cast<double>(k) / fps},
                 {"position", {cam.position.x, cam.position.y, cam.position.z}},
                 {"orientation", {cam.orientation.w, cam.orientation.x, cam.orientation.y, cam.orientation.z}},
                 {"fov", cam.fov_deg}});
  }
  return a.dump(1) + "\n";
}

Status run_render(const RenderCliOptions& c) {
  const bool path_only = !c.path.empty() && !c.write_path.empty() && c.out.empty();
  if (!c.write_path.empty() && c.path.empty()) return Status::input("render: --write-path goes with --path");
  if (c.out.empty() && !path_only) return Status::input("render: say where to write the image (-o OUT.png or OUT.exr)");
  if (!path_only) R1_TRY(render::check_image_extension(c.out));
  if (!c.path.empty() && c.orbit > 0) return Status::input("render: --path starts from one view (--view or --eye/--target), not --orbit");
  const int forms = (c.view_file.empty() ? 0 : 1) + (c.orbit > 0 ? 1 : 0) + (c.eye.empty() && c.target.empty() ? 0 : 1);
  if (forms > 1) return Status::input("render: give one of --view, --orbit and --eye/--target");
  if (c.orbit < 0 || c.orbit > 360) return Status::input("render: --orbit K needs 1 <= K <= 360");
  if (c.eye.empty() != c.target.empty()) return Status::input("render: --eye and --target go together");
  if (!(c.distance >= 0 && c.distance <= 1e7)) return Status::input("render: --distance must lie in [0, 1e7] scene units");

  R1_ASSIGN(const ChosenBackend chosen, c.backend.make());
  ProgressLine progress;
  const auto t0 = std::chrono::steady_clock::now();
  R1_ASSIGN(const Epoch e, read_epoch(c.dir));
  if (e.ids.empty()) return Status::input(c.dir + ": the epoch has no particles");
  // The cameras are placed from the reference's scene summary (centroid, fitted distance); the
  // frames are the chosen backend's (R1-BKD-016).
  render::Scene scene = render::make_scene(e);
  // --field neural (R1-NRF-031): the trained field draws pure T-infinity frames. The default,
  // auto, is neural where the epoch has its field (R1-NRF-031; r1 epoch writes one) and the
  // analytic oracle where it has none.
  if (c.field != "analytic" && c.field != "neural" && c.field != "auto")
    return Status::input("render: --field must be auto, analytic or neural");
  if (c.march != "skipping" && c.march != "literal") return Status::input("render: --march must be skipping or literal");
  const std::string nrf = field_path(c.dir, c.field_file);
  const bool use_neural = c.field == "neural" || (c.field == "auto" && fs::exists(nrf));
  if (c.march == "literal" && !use_neural) return Status::input("render: --march literal is the neural field's march: add --field neural");
  render::NeuralField neural;
  std::string neural_bytes;
  if (use_neural) {
    if (!fs::exists(nrf)) return Status::input(nrf + ": no neural field here (make it with r1 train-field " + c.dir + ")");
    R1_ASSIGN(const auto in, InputFile::open(nrf));
    neural_bytes = std::string(in->text());
    R1_ASSIGN(neural, render::decode_neural_field(neural_bytes, nrf, e.snapshot_digest));
    scene.neural = &neural;
  }
  // T0 content comes with the epoch (R1-RND-136): drawn by the reference renderer's content pass;
  // another backend draws a T0 particle as T1 and says so.
  R1_ASSIGN(const render::ContentSet content, render::read_epoch_content(c.dir, e.ids.size()));
  const render::ContentScene content_scene = render::make_content_scene(content, scene.n);
  const bool use_content = !content.entries.empty() && chosen.name == "reference";
  if (use_content) scene.content = &content_scene;
  if (!content.entries.empty() && !use_content && !c.quiet)
    std::printf("note: --backend %s does not draw T0 content; T0 particles are drawn as T1\n", chosen.name.c_str());

  render::View base;
  if (!c.view_file.empty()) {
    R1_ASSIGN(base, render::read_view_file(c.view_file));
  }
  if (!c.size.empty()) {
    R1_ASSIGN(const auto wh, parse_image_size(c.size, "render: --size"));
    base.width = wh.first, base.height = wh.second;
  }
  if (c.fov != 0) base.camera.fov_deg = c.fov;
  if (c.time != 0) base.time = c.time;
  if (c.no_edges) base.edges = false;
  if (c.no_labels) base.labels = false;
  if (c.no_field) base.field = false;
  std::vector<render::View> views;
  // R1-RND-007: the default orbit radius fits the whole scene into the vertical field of view.
  const double distance = c.distance > 0 ? c.distance : render::fit_distance(scene, base.camera.fov_deg);
  if (!c.eye.empty()) {
    render::View v = base;
    const render::Vec3 up = c.up.empty() ? render::Vec3{0, 0, 1} : render::Vec3{c.up[0], c.up[1], c.up[2]};
    v.camera.position = {c.eye[0], c.eye[1], c.eye[2]};
    R1_ASSIGN(v.camera.orientation, render::look_at(v.camera.position, {c.target[0], c.target[1], c.target[2]}, up));
    views.push_back(v);
  } else if (!c.view_file.empty()) {
    views.push_back(base);
  } else {
    // R1-RND-007: the default is the first orbit view.
    views = render::orbit_views(base, scene.centroid, distance, std::max(c.orbit, 1));
  }
  if (!c.path.empty()) {
    R1_TRY(render::validate_view(views.front(), "render"));
    R1_ASSIGN(views, path_views(c, e, scene, views.front()));
  }
  for (auto& v : views) R1_TRY(render::validate_view(v, "render"));
  if (!c.write_view.empty()) R1_TRY(write_file_atomic(c.write_view, render::view_toml(views.front())));
  if (path_only) {
    R1_TRY(write_file_atomic(c.write_path, path_json(views, c.fps)));
    if (!c.quiet) std::printf("%s: %zu poses of %s\n", c.write_path.c_str(), views.size(), c.path.c_str());
    return Status::ok();
  }

  // Render every view first, then write: a failed frame leaves no images behind (R1-ERR-003).
  std::vector<render::Image> images;
  std::vector<render::FrameStats> stats;
  const auto sink = progress.sink();
  for (std::size_t k = 0; k < views.size(); ++k) {
    const std::string stage = views.size() > 1 ? "render view " + std::to_string(k + 1) + "/" + std::to_string(views.size()) : "render";
    render::FrameStats st;
    const ProgressFn rows = [&](std::string_view, std::uint64_t d, std::uint64_t t) {
      if (sink) sink(stage, d, t);
    };
    // The backend draws the neural field too (RenderOptions::neural_field); T0 content only the
    // reference renderer's content pass draws.
    render::RenderOptions ro;
    ro.neural_field = neural_bytes;
    ro.field.literal = c.march == "literal";
    Result<render::Image> frame = use_content ? render::render_frame(scene, views[k], {}, &st, rows)
                                              : chosen.backend->render(e, views[k], ro, &st, rows);
    R1_ASSIGN(render::Image img, std::move(frame));
    images.push_back(std::move(img));
    stats.push_back(st);
  }
  progress.finish();
  for (std::size_t k = 0; k < views.size(); ++k) {
    const fs::path path = frame_path(c.out, static_cast<int>(k), static_cast<int>(views.size()));
    R1_TRY(render::write_image(images[k], path, render::srgb8_to_linear(views[k].background)));
    if (!c.quiet) print_stats(path, views[k], stats[k]);
    if (c.legibility) {
      // R1-RND-120..123.
      const render::Legibility l = render::legibility(scene, views[k]);
      std::printf("  legibility: %.1f%% of %llu shape particles overlapped by a nearer one; the middle 90%% of %llu visible "
                  "particles spans %.2f%% of the image; %.1f%% of all particles coincide with another\n",
                  100 * l.overlap_share, static_cast<unsigned long long>(l.shapes), static_cast<unsigned long long>(l.visible),
                  100 * l.core_share, 100 * l.coincident_share);
    }
    if (!c.quiet && use_neural)
      std::printf("  field: %s\n", stats[k].field_neural > 0 ? "neural"
                                      : "analytic (the frame is not pure T-infinity, R1-NRF-031)");
  }
  // The poses after the frames they belong to (R1-ERR-003: a failed frame leaves neither).
  if (!c.write_path.empty()) R1_TRY(write_file_atomic(c.write_path, path_json(views, c.fps)));
  if (!c.quiet) std::printf("%zu image%s in %.2f s\n", views.size(), views.size() == 1 ? "" : "s", seconds_since(t0));
  return Status::ok();
}

}  // namespace

void add_render(CLI::App& app, Runner& selected) {
  auto c = std::make_shared<RenderCliOptions>();
  auto* cmd = app.add_subcommand("render", "render views of an epoch (reference renderer: impostors, splats, field, edges)");
  cmd->add_option("EPOCH_DIR", c->dir, "epoch directory written by r1 epoch")->required();
  cmd->add_option("-o,--out", c->out, "output image: .png (display sRGB) or .exr (scene-linear float)");
  cmd->add_option("--view", c->view_file, "view file (TOML: [camera] [image] [tiers] [render])");
  cmd->add_option("--orbit", c->orbit, "K views on a circle around the scene: OUT-000.png ...");
  cmd->add_option("--distance", c->distance, "orbit radius in scene units (default: the whole scene fits)");
  cmd->add_option("--eye", c->eye, "camera position X Y Z (with --target)")->expected(3);
  cmd->add_option("--target", c->target, "point the camera looks at X Y Z")->expected(3);
  cmd->add_option("--up", c->up, "up direction X Y Z for --eye/--target (0 0 1)")->expected(3);
  cmd->add_option("--fov", c->fov, "vertical field of view in degrees, 30..110 (50)");
  cmd->add_option("--size", c->size, "image size WIDTHxHEIGHT (1280x720)");
  cmd->add_option("--time", c->time, "seconds, for the edge flow animation (0)");
  cmd->add_option("--write-view", c->write_view, "also write the (first) view used as a view file");
  cmd->add_flag("--no-edges", c->no_edges, "draw no edges");
  cmd->add_flag("--no-labels", c->no_labels, "draw no T1 labels");
  cmd->add_flag("--no-field", c->no_field, "no T-infinity field (sub-pixel particles vanish)");
  cmd->add_option("--field", c->field,
                  "T-infinity field: auto (neural where the epoch has its field.nrf, else analytic; the default), "
                  "analytic (the oracle) or neural (trained by r1 epoch or r1 train-field)");
  cmd->add_option("--field-file", c->field_file, "the trained field (default: EPOCH_DIR/field.nrf)");
  cmd->add_option("--march", c->march,
                  "the neural field's march: skipping (samples some node reaches, the default) or literal (every pixel's 128 samples, R1-NRF-033)");
  cmd->add_option("--path", c->path, "a camera path from the view: warp:QUERY (a title or hex id prefix) or follow:SECONDS; frames OUT-000 ...");
  cmd->add_option("--fps", c->fps, "frames per second along --path (30)");
  cmd->add_option("--write-path", c->write_path, "write the path's poses as JSON (without -o: only that)");
  cmd->add_flag("--legibility", c->legibility, "also print the frame's legibility measures (spec/render.md R1-RND-120)");
  cmd->add_flag("-q,--quiet", c->quiet, "no summary");
  c->backend.add_to(*cmd);
  cmd->callback([c, &selected] { selected = [c] { return run_render(*c); }; });
}

void add_train_field(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<TrainFieldOptions>();
  auto* cmd = app.add_subcommand("train-field", "train the T-infinity neural field of an epoch on its analytic field");
  cmd->add_option("EPOCH_DIR", o->dir, "epoch directory written by r1 epoch")->required();
  cmd->add_option("-o,--out", o->out, "output file (default: EPOCH_DIR/field.nrf)");
  cmd->add_option("--steps", o->config.steps, "Adam steps (default 120)")->check(CLI::Range(1u, 1000000u));
  cmd->add_option("--samples", o->config.samples, "training points (default 65536)")->check(CLI::Range(1u, 1u << 24));
  cmd->add_option("--batch", o->config.batch, "points per step (default 2048)")->check(CLI::Range(1u, 1u << 20));
  cmd->add_option("--threads", o->config.threads, "worker threads (default: every core; same bytes)");
  cmd->add_option("--block", o->block, "the network between its hidden layers: clifford (R-1.0 7.1's render block) or none")
      ->check(CLI::IsMember({"none", "clifford"}));
  cmd->add_flag("-q,--quiet", o->quiet, "no summary");
  cmd->callback([o, &selected] { selected = [o] { return run_train_field(*o); }; });
}

}  // namespace r1::cli
