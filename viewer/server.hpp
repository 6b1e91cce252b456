// `r1 view`'s server (spec/viewer.md R1-VIEW-001..015): serves the page (embedded in the binary)
// and the epoch it shows as a bundle of binary arrays, read-only, on 127.0.0.1 unless told
// otherwise. With `follow` it watches for newer epochs and switches to each one whole (R-1.0 2's
// double buffer): a generation's arrays are addressed by its number, so a page never mixes two.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/spec/status.hpp"

namespace r1::viewer {

// The epoch as the page draws it (R1-VIEW-010): the reference renderer's scene values, by name.
struct Bundle {
  std::uint64_t generation = 0;
  std::filesystem::path dir;
  std::string meta;  // meta.json
  std::vector<std::pair<std::string, std::string>> arrays;  // name -> bytes
  // For warp queries (R1-VIEW-020) and the next generation's prev.u32.
  std::vector<hemera::Digest> ids;
  std::vector<std::string> titles;
  std::vector<double> phi;
  // T0 content (R1-VIEW-070): the epoch's readable content files by their name under content/
  // ("K.png"), with the media type they are served as.
  struct Content {
    std::string name, bytes, media_type;
  };
  std::vector<Content> content;
  const std::string* array(std::string_view name) const;
  const Content* content_file(std::string_view name) const;
};

// Reads the epoch at `dir` and makes its bundle; `previous` (may be null) gives prev.u32, each
// particle's index in the previous generation (0xffffffff: new).
Result<std::shared_ptr<const Bundle>> make_bundle(const std::filesystem::path& dir, std::uint64_t generation,
                                                  const Bundle* previous);

// The epoch directory `--follow` shows under `path` (R1-VIEW-013): `path` itself when it holds a
// manifest.json, else its subdirectory whose manifest.json is newest (ties: the greater name);
// empty when there is none.
std::filesystem::path newest_epoch(const std::filesystem::path& path);

struct ServerOptions {
  std::string host = "127.0.0.1";
  int port = 8080;            // 0: any free port
  std::filesystem::path path; // an epoch directory, or with follow a directory of them
  bool follow = false;
  double poll_seconds = 0.5;
  std::function<void(const std::string&)> log;  // one line per event (switches, skipped epochs)
};

class Server {
 public:
  // Reads the first epoch and binds the port; errors are one line (bad epoch, busy port).
  static Result<std::unique_ptr<Server>> start(const ServerOptions& options);
  ~Server();
  int port() const;
  std::string url() const;
  void run();   // serves until stop(): blocks
  void stop();  // from any thread or a signal's flag watcher
  std::uint64_t generation() const;

 private:
  struct Impl;
  explicit Server(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The page's files, embedded at build time (viewer/page/).
struct Asset {
  const char* path;
  const char* content_type;
  const unsigned char* data;
  std::size_t size;
};
const std::vector<Asset>& page_assets();

}  // namespace r1::viewer
