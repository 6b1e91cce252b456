// Errors as values at stage boundaries (house style): Status and Result<T> (R1-ERR-001..004).
#pragma once

#include <cassert>
#include <optional>
#include <string>
#include <utility>
#include <variant>

namespace r1 {

// Kinds map to exit statuses of the r1 command (R1-ERR-002).
enum class ErrorKind {
  kInput = 2,     // malformed, truncated or out-of-range input; unknown options
  kOutput = 3,    // an output could not be written
  kInternal = 70  // a broken invariant inside r1 (a bug)
};

class Status {
 public:
  Status() = default;  // OK
  static Status ok() { return {}; }
  static Status error(ErrorKind kind, std::string message) { return Status(kind, std::move(message)); }
  static Status input(std::string message) { return error(ErrorKind::kInput, std::move(message)); }
  static Status output(std::string message) { return error(ErrorKind::kOutput, std::move(message)); }
  static Status internal(std::string message) { return error(ErrorKind::kInternal, std::move(message)); }

  bool is_ok() const { return !kind_.has_value(); }
  explicit operator bool() const { return is_ok(); }
  ErrorKind kind() const { return kind_.value_or(ErrorKind::kInternal); }
  const std::string& message() const { return message_; }
  int exit_code() const { return is_ok() ? 0 : static_cast<int>(*kind_); }

  // Prefixes the message with a location ("FILE: ..."), keeping the kind.
  Status with_prefix(const std::string& prefix) const {
    if (is_ok()) return *this;
    return Status(*kind_, prefix + message_);
  }

 private:
  Status(ErrorKind k, std::string m) : kind_(k), message_(one_line(std::move(m))) {}

  // Errors are one line (R1-ERR-001) even when they quote hostile input: a control byte other
  // than tab is shown as \xNN.
  static std::string one_line(std::string m) {
    std::string out;
    for (std::size_t i = 0; i < m.size(); ++i) {
      const auto u = static_cast<unsigned char>(m[i]);
      if ((u >= 0x20 && u != 0x7F) || u == '\t') {
        if (!out.empty()) out.push_back(m[i]);
        continue;
      }
      if (out.empty()) out.assign(m, 0, i);
      constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out.push_back(kHex[u >> 4]);
      out.push_back(kHex[u & 15]);
    }
    return out.empty() ? m : out;
  }
  std::optional<ErrorKind> kind_;
  std::string message_;
};

// A value or the Status that explains why there is none.
template <class T>
class Result {
 public:
  Result(T value) : v_(std::move(value)) {}  // NOLINT(google-explicit-constructor)
  Result(Status s) : v_(std::move(s)) { assert(!std::get<Status>(v_).is_ok()); }  // NOLINT

  bool is_ok() const { return std::holds_alternative<T>(v_); }
  explicit operator bool() const { return is_ok(); }
  const Status& status() const& {
    static const Status kOk;
    return is_ok() ? kOk : std::get<Status>(v_);
  }
  // On a temporary Result the status is returned by value: a reference into the temporary would
  // dangle as soon as the full expression ends (`R1_TRY(make().status())` read freed memory).
  Status status() && { return is_ok() ? Status() : std::get<Status>(std::move(v_)); }
  T& value() & { return std::get<T>(v_); }
  const T& value() const& { return std::get<T>(v_); }
  T&& value() && { return std::get<T>(std::move(v_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

 private:
  std::variant<T, Status> v_;
};

}  // namespace r1

namespace r1 {
inline const Status& status_of(const Status& s) { return s; }
template <class T>
const Status& status_of(const Result<T>& r) {
  return r.status();
}
}  // namespace r1

#define R1_CONCAT_INNER_(a, b) a##b
#define R1_CONCAT_(a, b) R1_CONCAT_INNER_(a, b)

// Returns early from a function returning Status or Result<U> when `expr` is an error.
#define R1_TRY(expr)                                                       \
  do {                                                                     \
    auto&& r1_try_ = (expr);                                               \
    if (!r1_try_.is_ok()) return ::r1::Status(::r1::status_of(r1_try_));   \
  } while (0)

// `R1_ASSIGN(auto x, f());` declares x from a Result, or returns its error.
#define R1_ASSIGN(lhs, expr) R1_ASSIGN_IMPL_(lhs, expr, R1_CONCAT_(r1_res_, __LINE__))
#define R1_ASSIGN_IMPL_(lhs, expr, tmp)                   \
  auto tmp = (expr);                                      \
  if (!tmp.is_ok()) return ::r1::Status(tmp.status());   \
  lhs = std::move(tmp).value()
