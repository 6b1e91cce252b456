// r1 hash [--tree] FILE...: Hemera digests of file bytes (R1-HASH-010).
#include <iostream>

#include "commands.hpp"
#include "r1/fixedpoint/hemera.hpp"
#include "r1/reference/input_file.hpp"

namespace r1::cli {

namespace {
struct HashOptions {
  bool tree = false;
  std::vector<std::string> files;
};

Status run_hash(const HashOptions& o) {
  for (const auto& path : o.files) {
    R1_ASSIGN(auto in, InputFile::open(path));
    const auto d = o.tree ? hemera::root_hash(in->bytes()) : hemera::hash(in->bytes());
    if (o.files.size() == 1) {
      std::cout << hemera::to_hex(d) << "\n";
    } else {
      std::cout << hemera::to_hex(d) << "  " << path << "\n";
    }
  }
  return Status::ok();
}
}  // namespace

void add_hash(CLI::App& app, Runner& selected) {
  auto opts = std::make_shared<HashOptions>();
  auto* cmd = app.add_subcommand("hash", "print the Hemera digest (64 hex digits) of each FILE's bytes");
  cmd->add_flag("--tree", opts->tree, "tree hash (root_hash over 4096-byte chunks) instead of the plain sponge");
  cmd->add_option("FILE", opts->files, "input file; - reads standard input")->required();
  cmd->callback([opts, &selected] { selected = [opts] { return run_hash(*opts); }; });
}

}  // namespace r1::cli
