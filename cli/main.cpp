// The r1 command: dispatch to subcommands; every error is one line on stderr and a non-zero
// exit status (R1-ERR-001..002).
#include <cstdio>
#include <exception>
#include <iostream>

#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"r1: reference implementation of the Cybergraph Render Specification R-1.0", "r1"};
  app.require_subcommand(0, 1);
  app.set_version_flag("--version", "r1 0.1.0");
  r1::cli::Runner selected;
  r1::cli::add_hash(app, selected);
  r1::cli::add_gen(app, selected);
  r1::cli::add_info(app, selected);
  r1::cli::add_convert(app, selected);
  r1::cli::add_edit(app, selected);
  r1::cli::add_drift(app, selected);
  r1::cli::add_epoch(app, selected);
  r1::cli::add_export(app, selected);
  r1::cli::add_spectrum(app, selected);
  r1::cli::add_render(app, selected);
  r1::cli::add_train_field(app, selected);
  r1::cli::add_golden(app, selected);
  r1::cli::add_conform(app, selected);
  r1::cli::add_diff(app, selected);
  r1::cli::add_bench(app, selected);
  r1::cli::add_view(app, selected);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "r1: " << e.what() << " (see r1 --help)\n";
    return 2;
  }
  if (!selected) {
    std::cerr << app.help();
    return 2;
  }
  try {
    const r1::Status s = selected();
    if (!s.is_ok()) {
      std::cerr << "r1: " << s.message() << "\n";
      return s.exit_code();
    }
  } catch (const std::bad_alloc&) {
    std::cerr << "r1: out of memory\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "r1: internal error: " << e.what() << "\n";
    return 70;
  }
  std::fflush(stdout);
  if (std::ferror(stdout)) {
    std::cerr << "r1: cannot write to standard output\n";
    return 3;
  }
  return r1::cli::verdict_exit();
}

int& r1::cli::verdict_exit() {
  static int code = 0;
  return code;
}
