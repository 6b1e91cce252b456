// rc::check with a cap on the number of cases, for properties whose cases are expensive (each
// solves graphs; the suites also run under the sanitizers). RC_PARAMS's seed is kept, and its
// max_success when lower.
#pragma once

#include <rapidcheck.h>

#include <algorithm>
#include <iostream>
#include <string>

namespace r1::test {

template <class Fn>
bool check_cases(const std::string& name, int cases, Fn fn) {
  rc::detail::TestParams params = rc::detail::configuration().testParams;
  params.maxSuccess = std::min(params.maxSuccess, cases);
  rc::detail::TestMetadata meta;
  meta.id = meta.description = name;
  const auto result = rc::detail::checkTestable(fn, meta, params);
  rc::detail::printResultMessage(result, std::cerr);
  std::cerr << '\n';
  return result.template is<rc::detail::SuccessResult>();
}

}  // namespace r1::test
