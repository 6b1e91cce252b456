// `r1 view`'s server (see server.hpp; spec/viewer.md R1-VIEW-001..015, R1-VIEW-070..072).
#include "server.hpp"

#include <httplib.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>
#include <unordered_map>

#include "r1/format/bytes.hpp"
#include "r1/reference/epoch_io.hpp"
#include "render/content.hpp"
#include "render/image.hpp"
#include "render/navigation.hpp"
#include "render/scene.hpp"
#include "render/view.hpp"

namespace r1::viewer {

namespace fs = std::filesystem;

const std::string* Bundle::array(std::string_view name) const {
  for (const auto& [k, v] : arrays)
    if (k == name) return &v;
  return nullptr;
}

const Bundle::Content* Bundle::content_file(std::string_view name) const {
  for (const Content& c : content)
    if (c.name == name) return &c;
  return nullptr;
}

namespace {

// The media type a content file is served as (R1-VIEW-071): images a browser shows by their
// type, text as UTF-8 plain text, everything else as bytes.
std::string media_type(const render::ContentEntry& e) {
  if (e.kind == render::ContentKind::kText) return "text/plain; charset=utf-8";
  if (e.kind == render::ContentKind::kImage) {
    if (e.type == "png") return "image/png";
    if (e.type == "jpg" || e.type == "jpeg") return "image/jpeg";
    if (e.type == "gif") return "image/gif";
    if (e.type == "webp") return "image/webp";
    if (e.type == "bmp") return "image/bmp";
  }
  return "application/octet-stream";
}

// Whether the page can show the file itself (an <img> or text), else it shows a card.
bool browser_shows(const std::string& media) { return media != "application/octet-stream"; }

nlohmann::json vec(const render::Vec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

// Labels one per line: control characters (a title may hold a newline) become spaces.
std::string label_lines(const render::Scene& s) {
  std::string out;
  for (const std::string& l : s.label) {
    for (char c : l) out.push_back(static_cast<unsigned char>(c) < 0x20 ? ' ' : c);
    out.push_back('\n');
  }
  return out;
}

}  // namespace

Result<std::shared_ptr<const Bundle>> make_bundle(const fs::path& dir, std::uint64_t generation, const Bundle* previous) {
  R1_ASSIGN(const Epoch e, read_epoch(dir));
  if (e.ids.empty()) return Status::input(dir.string() + ": the epoch has no particles");
  const render::Scene s = render::make_scene(e);
  auto b = std::make_shared<Bundle>();
  b->generation = generation;
  b->dir = dir;
  std::string pos, radius, phi, color, shape, edges, weights, a2, degree, clusters, nodes, prev;
  for (std::uint32_t p = 0; p < s.n; ++p) {
    for (const double x : {s.position[p].x, s.position[p].y, s.position[p].z}) format::put_f64(pos, x);
    format::put_f64(radius, s.radius[p]);
    format::put_f64(phi, s.phi[p]);
    for (const double x : {s.color[p].x, s.color[p].y, s.color[p].z}) format::put_f32(color, static_cast<float>(x));
    format::put_u8(shape, static_cast<std::uint8_t>(s.shape[p]));
    format::put_f64(degree, s.degree[p]);
    for (int l = 0; l < kLevels; ++l) format::put_u32(clusters, s.hierarchy->cluster_of[static_cast<std::size_t>(l)][p]);
  }
  // Per hierarchy node, level by level: the render scene's aggregates (R1-RND-013) and its parent,
  // for the page's edge bundles (R1-RND-064..066): centroid x y z, extent, max radius,
  // area-equivalent radius, linear colour r g b, parent id (-1 at the top level), box lo x y z, hi x y z,
  // member phi, member count.
  for (int l = 0; l < kLevels; ++l) {
    const auto level = static_cast<std::size_t>(l);
    for (std::size_t id = 0; id < s.nodes[level].size(); ++id) {
      const render::NodeData& d = s.nodes[level][id];
      const std::uint32_t parent = s.hierarchy->levels[level][id].parent;
      for (const double v : {d.centroid.x, d.centroid.y, d.centroid.z, d.extent, d.max_radius, d.radius, d.color.x, d.color.y,
                             d.color.z, parent == 0xFFFFFFFFu ? -1.0 : static_cast<double>(parent), d.lo.x, d.lo.y, d.lo.z,
                             d.hi.x, d.hi.y, d.hi.z, d.phi, static_cast<double>(d.count)})
        format::put_f64(nodes, v);
    }
  }
  for (const LayoutEdge& edge : s.edges) {
    format::put_u32(edges, edge.p);
    format::put_u32(edges, edge.q);
    format::put_f64(weights, Q32::from_raw(edge.w_raw).to_double());
    format::put_f64(a2, Q32::from_raw(edge.a2_raw).to_double());
  }
  // T0 content (R1-VIEW-070): read with the epoch (checked against content.tsv), served from memory.
  R1_ASSIGN(const render::ContentSet content, render::read_epoch_content(dir, e.ids.size()));
  nlohmann::json content_meta = nlohmann::json::array();
  for (const render::ContentEntry& c : content.entries) {
    const bool ok = c.status == render::ContentStatus::kOk;
    nlohmann::json j = {{"particle", c.particle},
                        {"status", render::content_status_name(c.status)},
                        {"kind", ok ? render::content_kind_name(c.kind) : "card"},
                        {"type", c.type},
                        {"source", c.source},
                        {"reason", c.reason},
                        {"url", nullptr},
                        {"bytes", c.bytes.size()}};
    if (ok) {
      const std::string media = media_type(c);
      // The page shows images and text itself; other files (and images a browser cannot show, such
      // as EXR) get a card naming the type, and a link only for what the browser can show.
      if (c.kind != render::ContentKind::kOther && !browser_shows(media)) j["kind"] = "other";
      const std::string name = c.file.substr(std::string("content/").size());
      j["url"] = "data/" + std::to_string(generation) + "/" + c.file;
      b->content.push_back({name, c.bytes, media});
    }
    content_meta.push_back(std::move(j));
  }
  b->ids = e.ids;
  b->titles = e.titles;
  b->phi = s.phi;
  if (previous) {
    // Each particle's index in the previous generation, by id (R1-VIEW-014).
    std::unordered_map<std::string_view, std::uint32_t> index;
    index.reserve(previous->ids.size());
    const auto key = [](const hemera::Digest& d) { return std::string_view(reinterpret_cast<const char*>(d.data()), d.size()); };
    for (std::uint32_t p = 0; p < previous->ids.size(); ++p) index.emplace(key(previous->ids[p]), p);
    for (std::uint32_t p = 0; p < s.n; ++p) {
      const auto it = index.find(key(b->ids[p]));
      format::put_u32(prev, it == index.end() ? 0xffffffffu : it->second);
    }
  }
  b->arrays = {{"positions.f64", std::move(pos)}, {"radius.f64", std::move(radius)}, {"phi.f64", std::move(phi)},
               {"color.f32", std::move(color)},   {"shape.u8", std::move(shape)},   {"edges.u32", std::move(edges)},
               {"weights.f64", std::move(weights)}, {"a2.f64", std::move(a2)},      {"degree.f64", std::move(degree)},
               {"clusters.u32", std::move(clusters)}, {"nodes.f64", std::move(nodes)}, {"labels.txt", label_lines(s)}};
  if (previous) b->arrays.emplace_back("prev.u32", std::move(prev));

  // The default camera is r1 render's (R1-RND-007): the first orbit view at the fitted distance.
  const render::View base;
  const render::View v = render::orbit_views(base, s.centroid, render::fit_distance(s, base.camera.fov_deg), 1).front();
  const auto& q = v.camera.orientation;
  const auto bg = render::srgb8_to_linear(base.background);
  std::vector<std::uint64_t> level_counts;
  for (const auto& level : s.nodes) level_counts.push_back(level.size());
  nlohmann::json m = {
      {"format", "r1-view-bundle"},
      {"version", 1},
      {"generation", generation},
      {"epoch", dir.filename().string()},
      {"snapshot", hemera::to_hex(e.snapshot_digest)},
      {"n", s.n},
      {"m", s.edges.size()},
      {"centroid", vec(s.centroid)},
      {"scene_radius", static_cast<double>(kSceneRadius)},
      {"tau0", s.tau0},
      {"median_radius", s.median_radius},
      {"extent", render::scene_extent(s)},
      {"camera", {{"position", vec(v.camera.position)}, {"orientation", {q.w, q.x, q.y, q.z}}, {"fov", v.camera.fov_deg}}},
      {"tiers", {{"t0", base.tiers.t0}, {"t1", base.tiers.t1}, {"t2", base.tiers.t2}, {"t3", base.tiers.t3}, {"band", base.tiers.band}}},
      {"background", {bg[0], bg[1], bg[2]}},
      {"hierarchy_levels", level_counts},
      {"arrays", nlohmann::json::array()},
      {"content", std::move(content_meta)},
  };
  for (const auto& [name, bytes] : b->arrays) m["arrays"].push_back({{"name", name}, {"bytes", bytes.size()}});
  b->meta = m.dump(1);
  return std::shared_ptr<const Bundle>(std::move(b));
}

fs::path newest_epoch(const fs::path& path) {
  std::error_code ec;
  if (fs::is_regular_file(path / "manifest.json", ec)) return path;
  fs::path best;
  fs::file_time_type best_time{};
  for (fs::directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_directory(ec)) continue;
    const fs::path manifest = it->path() / "manifest.json";
    const auto t = fs::last_write_time(manifest, ec);
    if (ec) {
      ec.clear();
      continue;
    }
    if (best.empty() || t > best_time || (t == best_time && it->path().filename() > best.filename())) best = it->path(), best_time = t;
  }
  return best;
}

struct Server::Impl {
  ServerOptions options;
  httplib::Server http;
  int port = 0;
  mutable std::mutex mutex;
  std::shared_ptr<const Bundle> current, previous;  // the page may still be fetching the previous one
  fs::path shown;                                   // the directory and manifest time of `current`
  fs::file_time_type shown_time{};
  std::string skipped;                              // the last epoch that failed to load (said once)
  std::atomic<bool> stopping{false};
  std::condition_variable wake;
  std::thread watcher;

  std::shared_ptr<const Bundle> bundle(std::uint64_t generation) const {
    std::lock_guard lock(mutex);
    if (current && current->generation == generation) return current;
    if (previous && previous->generation == generation) return previous;
    return nullptr;
  }
  std::shared_ptr<const Bundle> now() const {
    std::lock_guard lock(mutex);
    return current;
  }
  void log(const std::string& line) const {
    if (options.log) options.log(line);
  }

  // One look for a newer epoch (R1-VIEW-013); a bad one is reported once and skipped.
  void poll() {
    const fs::path dir = newest_epoch(options.path);
    if (dir.empty()) return;
    std::error_code ec;
    const auto t = fs::last_write_time(dir / "manifest.json", ec);
    if (ec) return;
    std::shared_ptr<const Bundle> cur = now();
    if (dir == shown && t == shown_time) return;
    const std::string key = dir.string() + "@" + std::to_string(t.time_since_epoch().count());
    if (key == skipped) return;
    auto next = make_bundle(dir, cur->generation + 1, cur.get());
    if (!next.is_ok()) {
      skipped = key;
      log("r1 view: skipped " + dir.string() + ": " + next.status().message());
      return;
    }
    {
      std::lock_guard lock(mutex);
      previous = current;
      current = next.value();
    }
    shown = dir, shown_time = t;
    log("r1 view: now showing " + dir.string() + " (generation " + std::to_string(next.value()->generation) + ")");
  }

  void routes() {
    // SO_REUSEADDR only: httplib's default adds SO_REUSEPORT, which lets a second server share a
    // busy port silently instead of failing (R1-VIEW-003).
    http.set_socket_options([](socket_t sock) {
      int yes = 1;
      setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });
    http.set_payload_max_length(4096);
    http.set_read_timeout(5, 0);
    http.set_write_timeout(30, 0);
    http.set_keep_alive_max_count(100);
    http.set_default_headers({{"Cache-Control", "no-store"}, {"X-Content-Type-Options", "nosniff"}});
    for (const Asset& a : page_assets()) {
      const std::string body(reinterpret_cast<const char*>(a.data), a.size);
      const std::string type = a.content_type;
      const auto serve = [body, type](const httplib::Request&, httplib::Response& res) { res.set_content(body, type.c_str()); };
      http.Get(a.path, serve);
      if (std::string_view(a.path) == "/index.html") http.Get("/", serve);
    }
    http.Get("/meta.json", [this](const httplib::Request&, httplib::Response& res) {
      res.set_content(now()->meta, "application/json");
    });
    // /data/GENERATION/NAME: one generation's array, or 404 once it is gone (the page re-reads meta).
    http.Get(R"(/data/([0-9]{1,19})/([a-z0-9]{1,16}\.[a-z0-9]{1,4}))", [this](const httplib::Request& req, httplib::Response& res) {
      const auto b = bundle(std::stoull(req.matches[1].str()));
      const std::string* bytes = b ? b->array(req.matches[2].str()) : nullptr;
      if (!bytes) {
        res.status = 404;
        res.set_content("no such array in this generation\n", "text/plain");
        return;
      }
      res.set_content(*bytes, req.matches[2].str().ends_with(".txt") ? "text/plain; charset=utf-8" : "application/octet-stream");
    });
    // /data/GENERATION/content/K[.ext]: a content file the epoch's content.tsv lists (R1-VIEW-071),
    // from memory; the name pattern admits no separators, and only listed names are found.
    http.Get(R"(/data/([0-9]{1,19})/content/([0-9]{1,10}(\.[a-z0-9]{1,16})?))", [this](const httplib::Request& req, httplib::Response& res) {
      const auto b = bundle(std::stoull(req.matches[1].str()));
      const Bundle::Content* c = b ? b->content_file(req.matches[2].str()) : nullptr;
      if (!c) {
        res.status = 404;
        res.set_content("no such content in this generation\n", "text/plain");
        return;
      }
      // Content is data, never a document that runs: a sandbox with nothing allowed.
      res.set_header("Content-Security-Policy", "sandbox; default-src 'none'");
      res.set_content(c->bytes, c->media_type);
    });
    // /find?q=QUERY: the particle a warp query names (R1-VIEW-020), in the current generation.
    http.Get("/find", [this](const httplib::Request& req, httplib::Response& res) {
      const std::string q = req.get_param_value("q");
      if (q.size() > 256) {
        res.status = 400;
        res.set_content(nlohmann::json{{"error", "warp: the query is longer than 256 bytes"}}.dump(), "application/json");
        return;
      }
      const auto b = now();
      const auto found = render::find_particle(b->ids, b->titles, b->phi, q);
      if (!found.is_ok()) {
        res.status = 404;
        res.set_content(nlohmann::json{{"error", found.status().message()}}.dump(), "application/json");
        return;
      }
      res.set_content(nlohmann::json{{"particle", found.value()}, {"generation", b->generation}}.dump(), "application/json");
    });
    http.set_error_handler([](const httplib::Request&, httplib::Response& res) {
      if (res.body.empty()) res.set_content(std::to_string(res.status) + "\n", "text/plain");
    });
  }

};

Server::Server(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Server::~Server() {
  stop();
  if (impl_->watcher.joinable()) impl_->watcher.join();
}

Result<std::unique_ptr<Server>> Server::start(const ServerOptions& options) {
  if (options.port < 0 || options.port > 65535) return Status::input("view: --port must be 0..65535");
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  fs::path dir = options.path;
  if (options.follow) {
    dir = newest_epoch(options.path);
    if (dir.empty()) return Status::input(options.path.string() + ": no epoch here to follow (no manifest.json in it or its subdirectories)");
  }
  R1_ASSIGN(impl->current, make_bundle(dir, 1, nullptr));
  impl->shown = dir;
  std::error_code ec;
  impl->shown_time = fs::last_write_time(dir / "manifest.json", ec);
  impl->routes();
  if (options.port == 0) {
    impl->port = impl->http.bind_to_any_port(options.host);
    if (impl->port <= 0) return Status::input("view: cannot listen on " + options.host + " (no free port, or not an address of this machine)");
  } else {
    if (!impl->http.bind_to_port(options.host, options.port))
      return Status::input("view: cannot listen on " + options.host + ":" + std::to_string(options.port) +
                           " (the port is busy, or the address is not this machine's)");
    impl->port = options.port;
  }
  return std::unique_ptr<Server>(new Server(std::move(impl)));
}

int Server::port() const { return impl_->port; }

std::string Server::url() const {
  const std::string& h = impl_->options.host;
  const std::string host = h.find(':') != std::string::npos ? "[" + h + "]" : (h == "0.0.0.0" ? "127.0.0.1" : h);
  return "http://" + host + ":" + std::to_string(impl_->port) + "/";
}

std::uint64_t Server::generation() const { return impl_->now()->generation; }

void Server::run() {
  Impl& m = *impl_;
  if (m.options.follow) {
    m.watcher = std::thread([&m] {
      std::mutex sleep_mutex;
      std::unique_lock lock(sleep_mutex);
      while (!m.stopping.load()) {
        m.wake.wait_for(lock, std::chrono::duration<double>(m.options.poll_seconds));
        if (!m.stopping.load()) m.poll();
      }
    });
  }
  m.http.listen_after_bind();
}

void Server::stop() {
  impl_->stopping.store(true);
  impl_->wake.notify_all();
  impl_->http.stop();
}

}  // namespace r1::viewer
