// The counting allocator of allocation_counter.hpp. Two entry points, each counted once:
//   - the global operator new, replaced in all its forms (C++ code, the standard library's containers);
//   - malloc and friends, wrapped at link time (-Wl,--wrap=malloc,...; tests/CMakeLists.txt): calls from the
//     objects linked into the executable reach __wrap_malloc, which counts and calls the C library's. Eigen
//     allocates with std::malloc, so this is what sees it.
// operator new allocates with __real_malloc, so that an allocation is not counted twice.
#include "allocation_counter.hpp"

#include <execinfo.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

extern "C" {
void* __real_malloc(std::size_t size);
void* __real_calloc(std::size_t count, std::size_t size);
void* __real_realloc(void* p, std::size_t size);
void* __real_aligned_alloc(std::size_t alignment, std::size_t size);
int __real_posix_memalign(void** p, std::size_t alignment, std::size_t size);
}

namespace {

std::atomic<int> g_regions{0};  // AllocationCount objects alive
std::atomic<long> g_allocations{0};
const bool g_trace = std::getenv("OCCTRACK_TRACE_ALLOCATIONS") != nullptr;
thread_local bool t_tracing = false;  // the backtrace's own allocations are not the code's

void note_allocation() {
  if (g_regions.load(std::memory_order_relaxed) == 0 || t_tracing) return;
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (!g_trace) return;
  t_tracing = true;
  void* frames[48];
  const int depth = backtrace(frames, 48);
  static const char kHeader[] = "--- counted allocation:\n";
  [[maybe_unused]] const ssize_t written = write(2, kHeader, sizeof(kHeader) - 1);
  backtrace_symbols_fd(frames, depth, 2);
  t_tracing = false;
}

void* allocate(std::size_t size) {
  note_allocation();
  return __real_malloc(size ? size : 1);
}

void* allocate_aligned(std::size_t size, std::align_val_t align) {
  note_allocation();
  void* p = nullptr;
  const std::size_t a = std::max(static_cast<std::size_t>(align), sizeof(void*));
  return __real_posix_memalign(&p, a, size ? size : 1) == 0 ? p : nullptr;
}

}  // namespace

namespace occtrack::test {

AllocationCount::AllocationCount() : start_(g_allocations.load()) { ++g_regions; }
AllocationCount::~AllocationCount() { --g_regions; }
long AllocationCount::allocations() const { return g_allocations.load() - start_; }

}  // namespace occtrack::test

// --- The C allocator, wrapped (the linker routes this program's calls here).
extern "C" {
void* __wrap_malloc(std::size_t size) {
  note_allocation();
  return __real_malloc(size);
}
void* __wrap_calloc(std::size_t count, std::size_t size) {
  note_allocation();
  return __real_calloc(count, size);
}
void* __wrap_realloc(void* p, std::size_t size) {
  if (size > 0) note_allocation();
  return __real_realloc(p, size);
}
void* __wrap_aligned_alloc(std::size_t alignment, std::size_t size) {
  note_allocation();
  return __real_aligned_alloc(alignment, size);
}
int __wrap_posix_memalign(void** p, std::size_t alignment, std::size_t size) {
  note_allocation();
  return __real_posix_memalign(p, alignment, size);
}
}

// --- The global operator new in every form; delete frees with free() (all of them come from the C allocator).
void* operator new(std::size_t size) {
  if (void* p = allocate(size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return allocate(size); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return allocate(size); }
void* operator new(std::size_t size, std::align_val_t align) {
  if (void* p = allocate_aligned(size, align)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size, std::align_val_t align) { return operator new(size, align); }
void* operator new(std::size_t size, std::align_val_t align, const std::nothrow_t&) noexcept {
  return allocate_aligned(size, align);
}
void* operator new[](std::size_t size, std::align_val_t align, const std::nothrow_t&) noexcept {
  return allocate_aligned(size, align);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
