// `r1 view`'s server (spec/viewer.md R1-VIEW-001..015) over HTTP on a free port: the page and the
// bundle's arrays equal the reference scene's values, paths outside what it serves are 404,
// hostile requests get errors without harm, a busy port and a bad epoch are one-line errors, and
// --follow switches to a newer epoch whole, mapping particles by id.
#include "server.hpp"

#include <gtest/gtest.h>
#include <httplib.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <nlohmann/json.hpp>
#include <thread>

#include "r1/reference/epoch_io.hpp"
#include "render/navigation.hpp"
#include "render/scene.hpp"
#include "render/view.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using r1::test::run_cli;

class ViewerServer : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new r1::test::TempDir;
    const std::string g = ((*dir_) / "ring.graph").string();
    ASSERT_EQ(run_cli({"gen", "ring", "--n", "60", "-o", g}).exit_code, 0);
    ASSERT_EQ(run_cli({"epoch", g, "-o", ((*dir_) / "a").string()}).exit_code, 0);
    const std::string g2 = ((*dir_) / "ring2.graph").string();
    ASSERT_EQ(run_cli({"gen", "ring", "--n", "64", "-o", g2}).exit_code, 0);
    ASSERT_EQ(run_cli({"epoch", g2, "-o", ((*dir_) / "b").string()}).exit_code, 0);
  }
  static void TearDownTestSuite() { delete dir_; }
  static fs::path epoch() { return (*dir_) / "a"; }

  // Starts a server on a free port and serves it on a thread until the test ends.
  void serve(const r1::viewer::ServerOptions& o) {
    auto s = r1::viewer::Server::start(o);
    ASSERT_TRUE(s.is_ok()) << s.status().message();
    server_ = std::move(s.value());
    thread_ = std::thread([this] { server_->run(); });
    client_ = std::make_unique<httplib::Client>("127.0.0.1", server_->port());
    for (int i = 0; i < 200 && !client_->Get("/meta.json"); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  void TearDown() override {
    if (server_) server_->stop();
    if (thread_.joinable()) thread_.join();
  }
  static r1::viewer::ServerOptions options(const fs::path& path) {
    r1::viewer::ServerOptions o;
    o.port = 0;
    o.path = path;
    return o;
  }
  nlohmann::json meta() { return nlohmann::json::parse(client_->Get("/meta.json")->body); }

  static r1::test::TempDir* dir_;
  std::unique_ptr<r1::viewer::Server> server_;
  std::thread thread_;
  std::unique_ptr<httplib::Client> client_;
};
r1::test::TempDir* ViewerServer::dir_ = nullptr;

TEST_F(ViewerServer, ServesThePageAndTheReferenceScene) {
  serve(options(epoch()));
  auto page = client_->Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("viewer.js"), std::string::npos);
  EXPECT_EQ(page->get_header_value("Content-Type"), "text/html; charset=utf-8");
  auto js = client_->Get("/viewer.js");
  ASSERT_TRUE(js);
  EXPECT_NE(js->body.find("r1view"), std::string::npos);

  const auto m = meta();
  EXPECT_EQ(m["n"], 60);
  EXPECT_EQ(m["generation"], 1);
  const auto e = r1::read_epoch(epoch());
  ASSERT_TRUE(e.is_ok());
  const r1::render::Scene s = r1::render::make_scene(*e);
  // Every array is the scene's value, bit for bit.
  auto pos = client_->Get("/data/1/positions.f64");
  ASSERT_TRUE(pos);
  ASSERT_EQ(pos->body.size(), 60u * 3 * 8);
  for (std::uint32_t p = 0; p < s.n; ++p) {
    double xyz[3];
    std::memcpy(xyz, pos->body.data() + 24 * p, 24);
    EXPECT_EQ(xyz[0], s.position[p].x);
    EXPECT_EQ(xyz[1], s.position[p].y);
    EXPECT_EQ(xyz[2], s.position[p].z);
  }
  auto radius = client_->Get("/data/1/radius.f64");
  ASSERT_TRUE(radius);
  double r5 = 0;
  std::memcpy(&r5, radius->body.data() + 5 * 8, 8);
  EXPECT_EQ(r5, s.radius[5]);
  auto edges = client_->Get("/data/1/edges.u32");
  ASSERT_TRUE(edges);
  EXPECT_EQ(edges->body.size(), s.edges.size() * 8);
  EXPECT_EQ(m["m"], s.edges.size());
  auto labels = client_->Get("/data/1/labels.txt");
  ASSERT_TRUE(labels);
  EXPECT_EQ(static_cast<std::size_t>(std::count(labels->body.begin(), labels->body.end(), '\n')), 60u);
  // Each listed array is served with the size meta.json gives.
  for (const auto& a : m["arrays"]) {
    auto r = client_->Get("/data/1/" + a["name"].get<std::string>());
    ASSERT_TRUE(r);
    EXPECT_EQ(r->body.size(), a["bytes"].get<std::size_t>()) << a["name"];
  }
}

TEST_F(ViewerServer, FindResolvesQueriesByTheReferenceRule) {
  serve(options(epoch()));
  const auto e = r1::read_epoch(epoch());
  ASSERT_TRUE(e.is_ok());
  const std::string hex = r1::hemera::to_hex(e->ids[17]);
  auto r = client_->Get("/find?q=" + hex.substr(0, 16));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(nlohmann::json::parse(r->body)["particle"], 17);
  auto none = client_->Get("/find?q=no%20such%20title");
  ASSERT_TRUE(none);
  EXPECT_EQ(none->status, 404);
  EXPECT_NE(nlohmann::json::parse(none->body)["error"].get<std::string>().find("no such title"), std::string::npos);
  auto empty = client_->Get("/find");
  ASSERT_TRUE(empty);
  EXPECT_EQ(empty->status, 404);
  auto huge = client_->Get("/find?q=" + std::string(300, 'a'));
  ASSERT_TRUE(huge);
  EXPECT_EQ(huge->status, 400);
}

TEST_F(ViewerServer, NothingOutsideWhatItServes) {
  serve(options(epoch()));
  for (const std::string path : {"/../manifest.json", "/data/1/../../etc/passwd", "/manifest.json", "/data/1/manifest.json",
                                 "/data/2/positions.f64", "/data/1/positions.q32", "/%2e%2e/%2e%2e/etc/passwd",
                                 "/data/99999999999999999999/positions.f64", "/viewer.js/..", "/index.html%00"}) {
    auto r = client_->Get(path);
    ASSERT_TRUE(r) << path;
    EXPECT_EQ(r->status, 404) << path;
    EXPECT_EQ(r->body.find("\"files\""), std::string::npos) << path;
  }
  // Other methods and oversized bodies are refused; the server keeps serving.
  auto post = client_->Post("/meta.json", std::string(100000, 'x'), "text/plain");
  ASSERT_TRUE(post);
  EXPECT_GE(post->status, 400);
  auto del = client_->Delete("/data/1/positions.f64");
  ASSERT_TRUE(del);
  EXPECT_GE(del->status, 400);
  // Raw garbage, a request line without a version, an oversized header: refused, nothing breaks.
  for (const std::string& raw : {std::string("GARBAGE\r\n\r\n"), std::string("GET /meta.json\r\n\r\n"),
                                "GET / HTTP/1.1\r\nHost: x\r\nX-Big: " + std::string(200000, 'a') + "\r\n\r\n",
                                std::string("GET /find?q=%ZZ%00 HTTP/1.1\r\nHost: x\r\n\r\n")}) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    ASSERT_GE(fd, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(server_->port()));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
    (void)!send(fd, raw.data(), raw.size(), MSG_NOSIGNAL);
    char buf[256];
    (void)!recv(fd, buf, sizeof buf, 0);
    close(fd);
  }
  auto ok = client_->Get("/meta.json");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200);
}

// T0 content (R1-VIEW-070..072): meta.json lists every entry of the epoch's content.tsv, the
// server serves the listed copies with their media type and nothing else under content/.
TEST_F(ViewerServer, ServesTheListedContentOnly) {
  auto e = r1::read_epoch(epoch());
  ASSERT_TRUE(e.is_ok()) << e.status().message();
  const fs::path site = (*dir_) / "site";
  fs::create_directories(site);
  const std::string png("\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x00\x00\x01\x00\x00\x00\x01\x08\x06\x00"
                        "\x00\x00\x1f\x15\xc4\x89\x00\x00\x00\x0d\x49\x44\x41\x54\x78\xda\x63\xfc\xcf\xc0\x50\x0f\x00\x04\x85\x01\x80"
                        "\x84\xa9\x8c\x21\x00\x00\x00\x00\x49\x45\x4e\x44\xae\x42\x60\x82",
                        67);
  r1::test::write_file(site / "dot.png", png);
  r1::test::write_file(site / "note.txt", "<script>alert(1)</script>\n");
  r1::test::write_file(site / "side.tsv", r1::hemera::to_hex(e->ids[3]) + "\tdot.png\n" + r1::hemera::to_hex(e->ids[5]) +
                                              "\tnote.txt\n" + r1::hemera::to_hex(e->ids[7]) + "\t../ring.graph\n");
  const fs::path with = (*dir_) / "with-content";
  const auto made = run_cli({"epoch", ((*dir_) / "ring.graph").string(), "-q", "--content", (site / "side.tsv").string(), "-o",
                             with.string()});
  ASSERT_EQ(made.exit_code, 0) << made.err;
  serve(options(with));
  const nlohmann::json m = meta();
  ASSERT_EQ(m["content"].size(), 3u);
  EXPECT_EQ(m["content"][0]["particle"], 3);
  EXPECT_EQ(m["content"][0]["kind"], "image");
  EXPECT_EQ(m["content"][0]["url"], "data/1/content/3.png");
  EXPECT_EQ(m["content"][1]["kind"], "text");
  EXPECT_EQ(m["content"][2]["status"], "refused");
  EXPECT_TRUE(m["content"][2]["url"].is_null());
  auto img = client_->Get("/data/1/content/3.png");
  ASSERT_TRUE(img);
  EXPECT_EQ(img->status, 200);
  EXPECT_EQ(img->body, png);
  EXPECT_EQ(img->get_header_value("Content-Type"), "image/png");
  EXPECT_NE(img->get_header_value("Content-Security-Policy").find("sandbox"), std::string::npos);
  auto txt = client_->Get("/data/1/content/5.txt");
  ASSERT_TRUE(txt);
  EXPECT_EQ(txt->status, 200);
  EXPECT_EQ(txt->get_header_value("Content-Type"), "text/plain; charset=utf-8");
  EXPECT_EQ(txt->body, "<script>alert(1)</script>\n");
  // Unlisted names, the refused file, other generations, the index itself and climbs: 404.
  for (const std::string path : {"/data/1/content/4.png", "/data/1/content/3.txt", "/data/1/content/7.graph", "/data/1/content/7",
                                 "/data/2/content/3.png", "/data/1/content.tsv", "/data/1/content/../manifest.json",
                                 "/data/1/content/%2e%2e/manifest.json", "/data/1/content/3.png/..", "/content/3.png",
                                 "/data/1/content/", "/data/1/content/3.png%00"}) {
    auto r = client_->Get(path);
    ASSERT_TRUE(r) << path;
    EXPECT_EQ(r->status, 404) << path;
  }
}

TEST_F(ViewerServer, BusyPortAndBadEpochAreOneLineErrors) {
  serve(options(epoch()));
  auto o = options(epoch());
  o.port = server_->port();
  const auto busy = r1::viewer::Server::start(o);
  ASSERT_FALSE(busy.is_ok());
  EXPECT_NE(busy.status().message().find("busy"), std::string::npos);
  EXPECT_EQ(busy.status().message().find('\n'), std::string::npos);
  const auto missing = r1::viewer::Server::start(options((*dir_) / "nothing"));
  ASSERT_FALSE(missing.is_ok());
  EXPECT_NE(missing.status().message().find("nothing"), std::string::npos);
  auto f = options((*dir_) / "nothing");
  f.follow = true;
  EXPECT_FALSE(r1::viewer::Server::start(f).is_ok());
}

TEST_F(ViewerServer, FollowSwitchesToANewerEpochWhole) {
  r1::test::TempDir watch;
  fs::copy(epoch(), watch / "e1", fs::copy_options::recursive);
  auto o = options(watch.path());
  o.follow = true;
  o.poll_seconds = 0.05;
  serve(o);
  EXPECT_EQ(meta()["generation"], 1);
  // A damaged epoch is skipped and the current one stays.
  fs::copy((*dir_) / "b", watch / "e2", fs::copy_options::recursive);
  {
    std::FILE* f = std::fopen((watch / "e2" / "positions.q32").c_str(), "r+b");
    ASSERT_NE(f, nullptr);
    std::fputc(0x55, f);
    std::fclose(f);
  }
  fs::last_write_time(watch / "e2" / "manifest.json", fs::file_time_type::clock::now() + std::chrono::seconds(5));
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  EXPECT_EQ(meta()["generation"], 1);
  EXPECT_EQ(meta()["n"], 60);
  // A good newer one is shown whole, with each particle's index in the previous generation.
  fs::copy((*dir_) / "b", watch / "e3", fs::copy_options::recursive);
  fs::last_write_time(watch / "e3" / "manifest.json", fs::file_time_type::clock::now() + std::chrono::seconds(10));
  nlohmann::json m;
  for (int i = 0; i < 100; ++i) {
    m = meta();
    if (m["generation"] == 2) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_EQ(m["generation"], 2);
  EXPECT_EQ(m["n"], 64);
  auto prev = client_->Get("/data/2/prev.u32");
  ASSERT_TRUE(prev);
  ASSERT_EQ(prev->body.size(), 64u * 4);
  const auto a = r1::read_epoch(epoch());
  const auto b = r1::read_epoch((*dir_) / "b");
  ASSERT_TRUE(a.is_ok() && b.is_ok());
  for (std::uint32_t p = 0; p < 64; ++p) {
    std::uint32_t k = 0;
    std::memcpy(&k, prev->body.data() + 4 * p, 4);
    const auto it = std::find(a->ids.begin(), a->ids.end(), b->ids[p]);
    EXPECT_EQ(k, it == a->ids.end() ? 0xffffffffu : static_cast<std::uint32_t>(it - a->ids.begin())) << p;
  }
  // The previous generation's arrays stay readable for a page still fetching them.
  auto old = client_->Get("/data/1/positions.f64");
  ASSERT_TRUE(old);
  EXPECT_EQ(old->status, 200);
}

TEST_F(ViewerServer, CliErrorsAreOneLine) {
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"view", ((*dir_) / "nothing").string(), "--port", "0"},
        std::vector<std::string>{"view", epoch().string(), "--port", "70000"},
        std::vector<std::string>{"view", epoch().string(), "--follow", "--poll", "0"},
        std::vector<std::string>{"render", epoch().string(), "--path", "fly:somewhere", "--write-path", ((*dir_) / "p.json").string()},
        std::vector<std::string>{"render", epoch().string(), "--write-path", ((*dir_) / "p.json").string()},
        std::vector<std::string>{"render", epoch().string(), "--path", "warp:no such title", "--write-path", ((*dir_) / "p.json").string()},
        std::vector<std::string>{"render", epoch().string(), "--path", "follow:-1", "--write-path", ((*dir_) / "p.json").string()}}) {
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << args[0] << " " << args[2];
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_FALSE(fs::exists((*dir_) / "p.json"));
}

// R1-VIEW-050: r1 render --path writes the reference's flight: pose 0 the start camera, the last
// the warp's end pose, smooth-step in between; follow-flow's poses are its steps.
TEST_F(ViewerServer, RenderPathPosesAreTheNavigationRules) {
  const auto e = r1::read_epoch(epoch());
  ASSERT_TRUE(e.is_ok());
  const r1::render::Scene scene = r1::render::make_scene(*e);
  const std::string hex = r1::hemera::to_hex(e->ids[9]).substr(0, 20);
  const fs::path out = (*dir_) / "warp.json";
  const auto r = run_cli({"render", epoch().string(), "--eye", "300", "200", "100", "--target", "0", "0", "0", "--path", "warp:" + hex,
                          "--fps", "10", "--write-path", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto poses = nlohmann::json::parse(r1::test::read_file(out));
  ASSERT_EQ(poses.size(), 6u);  // t = 0, 0.1, ..., 0.5
  // The start view as r1 render makes it: look-at, then validated (which renormalises).
  r1::render::View v;
  v.camera.position = {300, 200, 100};
  v.camera.orientation = r1::render::look_at(v.camera.position, {0, 0, 0}, {0, 0, 1}).value();
  ASSERT_TRUE(r1::render::validate_view(v, "test").is_ok());
  const r1::render::Camera start = v.camera;
  const r1::render::Camera end = r1::render::warp_end(start, scene, 9);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    r1::render::View at = v;  // each frame's view is validated too
    at.camera = r1::render::warp_at(start, end, 0.1 * static_cast<double>(k));
    ASSERT_TRUE(r1::render::validate_view(at, "test").is_ok());
    const r1::render::Camera& c = at.camera;
    EXPECT_EQ(poses[k]["position"][0].get<double>(), c.position.x) << k;
    EXPECT_EQ(poses[k]["position"][2].get<double>(), c.position.z) << k;
    EXPECT_EQ(poses[k]["orientation"][0].get<double>(), c.orientation.w) << k;
  }
  EXPECT_NEAR(r1::render::length(end.position - scene.position[9]), 3 * scene.radius[9], 1e-9);
  // Frames too: one per pose.
  const auto frames = run_cli({"render", epoch().string(), "--eye", "300", "200", "100", "--target", "0", "0", "0", "--path",
                               "follow:0.2", "--fps", "10", "--size", "32x18", "-q", "-o", ((*dir_) / "f.png").string()});
  ASSERT_EQ(frames.exit_code, 0) << frames.err;
  for (const char* name : {"f-000.png", "f-001.png", "f-002.png"}) EXPECT_TRUE(fs::exists((*dir_) / name)) << name;
  EXPECT_FALSE(fs::exists((*dir_) / "f-003.png"));
}

}  // namespace
