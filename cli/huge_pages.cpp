// The r1 command's operator new: large blocks (the layout graph's arrays, the spectral panel, the
// epoch's per-particle arrays) are advised onto transparent huge pages before anything touches
// them (madvise MADV_HUGEPAGE, which Linux honours when THP is "always" or "madvise"). A 10^6
// epoch first-touches some 2 GB; with 4 KiB pages that is half a million page faults, which on a
// virtual machine cost more than zeroing the pages (README, "Huge pages"). Speed only: no value
// changes, and where the advice is refused the pages are ordinary ones. R1_HUGE_PAGES=0 in the
// environment leaves every block on ordinary pages (a smaller peak where huge pages are only
// partly used). Sanitizer builds keep their own allocator.
#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <string_view>

#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(memory_sanitizer) || __has_feature(thread_sanitizer)
#define R1_KEEP_ALLOCATOR 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define R1_KEEP_ALLOCATOR 1
#endif

#ifndef R1_KEEP_ALLOCATOR

namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;
// Blocks from one huge page up (a smaller block holds no whole huge page). glibc serves most of
// them by mmap, untouched; one it takes from its heap gets the advice for its pages not yet
// touched.
constexpr std::size_t kAdviseFrom = kHugePage;

void* allocate(std::size_t n) {
  void* p = std::malloc(n == 0 ? 1 : n);
  if (p == nullptr) throw std::bad_alloc();
  static const bool advise = [] {
    const char* v = std::getenv("R1_HUGE_PAGES");
    return v == nullptr || std::string_view(v) != "0";
  }();
  if (n >= kAdviseFrom && advise) {
    // The huge pages wholly inside the block; the advice covers whole pages only.
    const auto begin = (reinterpret_cast<std::uintptr_t>(p) + kHugePage - 1) & ~(kHugePage - 1);
    const auto end = (reinterpret_cast<std::uintptr_t>(p) + n) & ~(kHugePage - 1);
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
  }
  return p;
}

}  // namespace

void* operator new(std::size_t n) { return allocate(n); }
void* operator new[](std::size_t n) { return allocate(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return allocate(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return allocate(n);
  } catch (...) {
    return nullptr;
  }
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

#endif
