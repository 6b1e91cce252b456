// r1 view EPOCH_DIR [--port P] [--host H] [--follow]: the local web viewer (spec/viewer.md
// R1-VIEW-001..015). Serves until interrupted (Ctrl-C or SIGTERM), then exits 0.
#include <pthread.h>

#include <csignal>
#include <cstdio>
#include <thread>

#include "commands.hpp"
#include "server.hpp"

namespace r1::cli {

namespace {

struct ViewCliOptions {
  std::string path, host = "127.0.0.1";
  int port = 8080;
  bool follow = false;
  double poll = 0.5;
};

Status run_view(const ViewCliOptions& c) {
  if (!(c.poll >= 0.05 && c.poll <= 3600)) return Status::input("view: --poll must lie in [0.05, 3600] seconds");
  viewer::ServerOptions o;
  o.host = c.host;
  o.port = c.port;
  o.path = c.path;
  o.follow = c.follow;
  o.poll_seconds = c.poll;
  o.log = [](const std::string& line) {
    std::fprintf(stderr, "%s\n", line.c_str());
    std::fflush(stderr);
  };
  // SIGINT and SIGTERM go to one thread that stops the server (the others never see them).
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  R1_ASSIGN(auto server, viewer::Server::start(o));
  std::printf("r1 view: %s%s at %s (Ctrl-C to stop)\n", c.follow ? "following " : "serving ", c.path.c_str(), server->url().c_str());
  std::fflush(stdout);
  std::thread stopper([&server, signals] {
    int sig = 0;
    sigwait(&signals, &sig);
    server->stop();
  });
  server->run();
  // Wake the stopper if the server ended on its own.
  pthread_kill(stopper.native_handle(), SIGTERM);
  stopper.join();
  return Status::ok();
}

}  // namespace

void add_view(CLI::App& app, Runner& selected) {
  auto c = std::make_shared<ViewCliOptions>();
  auto* cmd = app.add_subcommand("view", "serve an epoch to the web viewer (WebGL2) on 127.0.0.1");
  cmd->add_option("EPOCH_DIR", c->path, "epoch directory written by r1 epoch (with --follow: a directory of them, or one to watch)")
      ->required();
  cmd->add_option("--port", c->port, "TCP port (8080; 0 = any free port)")->check(CLI::Range(0, 65535));
  cmd->add_option("--host", c->host, "address to listen on (127.0.0.1; 0.0.0.0 exposes the viewer to the network)");
  cmd->add_flag("--follow", c->follow, "switch to each newer epoch as it appears, easing positions between them");
  cmd->add_option("--poll", c->poll, "with --follow: seconds between looks for a newer epoch (0.5)");
  cmd->callback([c, &selected] { selected = [c] { return run_view(*c); }; });
}

}  // namespace r1::cli
