#pragma once

// Helpers for the far_io tests: a temporary folder, file writing, binary byte builders and an
// error matcher.

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include "far/base/result.h"
#include "far/model/mesh.h"

namespace far::testing {

/// A fresh folder under the system temp folder, removed with everything in it on destruction.
class TempDir {
 public:
  TempDir() {
    std::random_device device;
    std::mt19937_64 random(device());
    path_ = std::filesystem::temp_directory_path() / ("far_io_test_" + std::to_string(random()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

/// Writes `bytes` to `path`, creating folders as needed.
inline void WriteFile(const std::filesystem::path& path, std::string_view bytes) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << path;
}

/// Reads the whole file at `path`.
inline std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// Appends scalars in little- or big-endian order to a byte string.
class Bytes {
 public:
  explicit Bytes(bool big_endian = false) : big_endian_(big_endian) {}
  template <typename T>
  Bytes& Put(T value) {
    char buffer[sizeof(T)];
    std::memcpy(buffer, &value, sizeof(T));
    if (big_endian_) {
      for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(buffer[i], buffer[sizeof(T) - 1 - i]);
    }
    bytes_.append(buffer, sizeof(T));
    return *this;
  }
  Bytes& Text(std::string_view text) {
    bytes_.append(text);
    return *this;
  }
  const std::string& str() const { return bytes_; }
  size_t size() const { return bytes_.size(); }

 private:
  bool big_endian_;
  std::string bytes_;
};

/// Checks that `result` failed with `code` and a message containing `substring`.
template <typename T>
::testing::AssertionResult IsError(const Result<T>& result, ErrorCode code,
                                   std::string_view substring) {
  if (result.ok()) return ::testing::AssertionFailure() << "expected an error, got success";
  const Error& error = result.error();
  if (error.code != code || error.message.find(substring) == std::string::npos) {
    return ::testing::AssertionFailure() << "expected " << ToString(code) << " containing \""
                                         << substring << "\", got " << ToString(error);
  }
  return ::testing::AssertionSuccess();
}

/// Checks that two meshes have exactly the same positions and triangles.
inline ::testing::AssertionResult SameMesh(const Mesh& a, const Mesh& b) {
  if (a.p_MV.size() != b.p_MV.size() || a.triangles.size() != b.triangles.size()) {
    return ::testing::AssertionFailure()
           << "sizes differ: " << a.p_MV.size() << "/" << a.triangles.size() << " vs "
           << b.p_MV.size() << "/" << b.triangles.size();
  }
  for (size_t v = 0; v < a.p_MV.size(); ++v) {
    if (a.p_MV[v] != b.p_MV[v]) {
      return ::testing::AssertionFailure()
             << "vertex " << v << " differs: " << a.p_MV[v].transpose() << " vs "
             << b.p_MV[v].transpose();
    }
  }
  for (size_t t = 0; t < a.triangles.size(); ++t) {
    if (a.triangles[t] != b.triangles[t]) {
      return ::testing::AssertionFailure() << "triangle " << t << " differs";
    }
  }
  return ::testing::AssertionSuccess();
}

}  // namespace far::testing
