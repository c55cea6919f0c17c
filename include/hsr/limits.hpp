// The memory limit: one process-wide bound on what a single request (an image's buffers, a
// generated scene, a BSP tree or depth sort, a batch of views) may allocate, checked up front
// from the request's own size, so that an absurd request fails with a clear InputError instead
// of meeting the kernel's out-of-memory killer. The CLI sets it from --max-memory (docs/cli.md).
#pragma once
#include <cstdint>
#include <string>

namespace hsr {

/// The limit in bytes: the one set, else the machine's available memory when first asked
/// (/proc/meminfo's MemAvailable; 8 GiB where that cannot be read).
uint64_t memoryLimit();
/// Sets the limit (bytes; 0 restores the machine's default). Thread-safe.
void setMemoryLimit(uint64_t bytes);
/// Throws InputError keyed Setting::MaxMemory, subject `what` (the request), when `bytes` exceeds
/// the limit: "WHAT needs about N MiB, more than the memory limit of M MiB".
void checkMemory(double bytes, const std::string& what);
/// Parses a size for the limit: a number with an optional unit K, M, G or T (powers of 1024; "B"
/// allowed after it: "512M", "2GiB", "1.5G"). Throws InputError naming `what` (a front end passes
/// its own name of the setting, the CLI "--max-memory").
uint64_t parseMemorySize(const std::string& text, const std::string& what = "memory limit");

}  // namespace hsr
