#pragma once

// Shared by the fuzz targets whose input has a structure (datagrams on channels, rounds on a
// ring): a reader of the fuzzer's bytes, front to back, the check that turns a broken
// invariant into a crash libFuzzer reports, and a count of open descriptors for leak checks. The
// seed writer (make_seeds.cc) writes inputs with the same layouts, so every layout is documented
// once, in its target's file.

#include <dirent.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>

namespace far::fuzz {

/// Aborts (a crash for libFuzzer, with the input saved) when an invariant does not hold.
#define FAR_FUZZ_CHECK(condition)                                                            \
  do {                                                                                       \
    if (!(condition)) {                                                                      \
      std::fprintf(stderr, "%s:%d: invariant failed: %s\n", __FILE__, __LINE__, #condition); \
      std::abort();                                                                          \
    }                                                                                        \
  } while (false)

/// Reads the fuzzer's bytes front to back. Past the end every value reads as zero and every
/// byte range as empty, so any input is a valid sequence of operations.
class FuzzInput {
 public:
  FuzzInput(const uint8_t* data, size_t size) : data_(data), size_(size) {}

  bool empty() const { return pos_ == size_; }
  size_t left() const { return size_ - pos_; }

  /// The next sizeof(T) bytes as a host-order T (zero-filled past the end).
  template <typename T>
  T Take() {
    static_assert(std::is_trivially_copyable_v<T>);
    T value{};
    const size_t n = sizeof(T) < left() ? sizeof(T) : left();
    std::memcpy(&value, data_ + pos_, n);
    pos_ += n;
    return value;
  }

  /// The next `count` bytes, or fewer at the end.
  std::span<const uint8_t> TakeBytes(size_t count) {
    const size_t n = count < left() ? count : left();
    std::span<const uint8_t> bytes(data_ + pos_, n);
    pos_ += n;
    return bytes;
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

// The process's open file descriptors (entries of /proc/self/fd): what a harness compares
// before and after an input to find a descriptor the code under test leaked.
inline int OpenDescriptors() {
  int count = 0;
  DIR* dir = opendir("/proc/self/fd");
  FAR_FUZZ_CHECK(dir != nullptr);
  while (readdir(dir) != nullptr) ++count;
  closedir(dir);
  return count;
}

// The process's open descriptors and what each one is ("3 -> socket:[123]"), one per line: what
// a harness prints when a descriptor count does not come back, so that a rare failure names the
// descriptor instead of only its count.
inline std::string DescribeDescriptors() {
  std::string text;
  DIR* dir = opendir("/proc/self/fd");
  if (dir == nullptr) return "(cannot read /proc/self/fd)\n";
  while (const dirent* entry = readdir(dir)) {
    if (entry->d_name[0] == '.') continue;
    const std::string path = std::string("/proc/self/fd/") + entry->d_name;
    char target[256] = {};
    const ssize_t length = readlink(path.c_str(), target, sizeof(target) - 1);
    text += std::string(entry->d_name) + " -> " + (length > 0 ? target : "?") + "\n";
  }
  closedir(dir);
  return text;
}

}  // namespace far::fuzz
