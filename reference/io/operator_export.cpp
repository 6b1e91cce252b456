// The spectral operator as a Matrix Market file (R1-SPEC-070), written atomically: for
// `r1 spectrum --laplacian` and the eigsh comparison.
#include <charconv>
#include <string>
#include <type_traits>

#include "r1/reference/atomic_file.hpp"
#include "r1/reference/operator_export.hpp"

namespace r1 {

// ---- Matrix Market export (R1-SPEC-070) -------------------------------------------------------------

namespace {
double as_double(fx::Q32 v) { return v.to_double(); }
double as_double(double v) { return v; }

void append_double(std::string& out, double v) {
  char buf[40];
  // Shortest text that reads back as the same double: exact for every Q32 entry (raw <= 2^32).
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}
}  // namespace

template <class Scalar>
Status write_operator_matrix_market(const SpectralOperator<Scalar>& op, const std::string& path) {
  const Graph& gr = *op.graph;
  AtomicFile f(path);
  R1_TRY(f.open());
  std::string buf;
  buf += "%%MatrixMarket matrix coordinate real symmetric\n";
  buf += "% r1 spectral operator (R1-SPEC-070): L = I - M";
  buf += op.g.empty() ? "" : " - g g^T with g on the %r1-rank-one lines";
  buf += ", rho = " + op.rho.to_string() + ", domain ";
  buf += std::is_same_v<Scalar, double> ? "fp64\n" : "q32\n";
  for (std::size_t i = 0; i < op.g.size(); ++i) {
    buf += "%r1-rank-one " + std::to_string(i + 1) + " ";
    append_double(buf, as_double(op.g[i]));
    buf += "\n";
    if (buf.size() > (1u << 20)) {
      R1_TRY(f.write(buf));
      buf.clear();
    }
  }
  const std::uint64_t lower = gr.nnz() / 2 + op.n;
  buf += std::to_string(op.n) + " " + std::to_string(op.n) + " " + std::to_string(lower) + "\n";
  for (std::uint32_t i = 0; i < op.n; ++i) {
    for (std::uint64_t k = gr.row_ptr[i]; k < gr.row_ptr[i + 1] && gr.col[k] < i; ++k) {
      buf += std::to_string(i + 1) + " " + std::to_string(gr.col[k] + 1) + " ";
      append_double(buf, -as_double(op.m[k]));
      buf += "\n";
    }
    buf += std::to_string(i + 1) + " " + std::to_string(i + 1) + " 1\n";
    if (buf.size() > (1u << 20)) {
      R1_TRY(f.write(buf));
      buf.clear();
    }
  }
  R1_TRY(f.write(buf));
  return f.commit();
}

template Status write_operator_matrix_market(const SpectralOperator<fx::Q32>&, const std::string&);
template Status write_operator_matrix_market(const SpectralOperator<double>&, const std::string&);

}  // namespace r1
