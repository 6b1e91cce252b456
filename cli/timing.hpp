// Wall-clock seconds and peak memory for the commands' timing reports.
#pragma once

#include <sys/resource.h>

#include "r1/spec/progress.hpp"  // seconds_since

namespace r1::cli {

using r1::seconds_since;

// Peak resident memory of this process in MiB.
inline double peak_rss_mib() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

}  // namespace r1::cli
