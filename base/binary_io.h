#pragma once
// Little-endian binary files with a magic and a format version (docs/design.md §3): a writer that appends
// numbers, arrays and strings to a buffer, and a reader that checks every length against what is left, so a
// truncated or hostile file gives an error naming the file, never an over-read or a huge allocation.

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace p2n {

class BinaryWriter {
 public:
  template <typename T>
  void Put(T value) {
    static_assert(std::is_arithmetic_v<T>);
    const auto* bytes = reinterpret_cast<const char*>(&value);
    buffer_.insert(buffer_.end(), bytes, bytes + sizeof(T));
  }
  template <typename T>
  void PutArray(const T* values, size_t count) {
    static_assert(std::is_arithmetic_v<T>);
    Put<uint64_t>(count);
    const auto* bytes = reinterpret_cast<const char*>(values);
    buffer_.insert(buffer_.end(), bytes, bytes + count * sizeof(T));
  }
  template <typename T>
  void PutVector(const std::vector<T>& values) {
    PutArray(values.data(), values.size());
  }
  void PutString(const std::string& text) { PutArray(text.data(), text.size()); }
  void PutBytes(const char* bytes, size_t count) { buffer_.insert(buffer_.end(), bytes, bytes + count); }

  const std::vector<char>& buffer() const { return buffer_; }

 private:
  std::vector<char> buffer_;
};

// Reads what BinaryWriter wrote; std::runtime_error naming `source` when the data runs out or a length is
// impossible.
class BinaryReader {
 public:
  BinaryReader(std::vector<char> data, std::string source) : data_(std::move(data)), source_(std::move(source)) {}

  template <typename T>
  T Get() {
    static_assert(std::is_arithmetic_v<T>);
    T value;
    std::memcpy(&value, Take(sizeof(T)), sizeof(T));
    return value;
  }
  template <typename T>
  std::vector<T> GetVector(size_t expected = SIZE_MAX) {
    const uint64_t count = Get<uint64_t>();
    if (expected != SIZE_MAX && count != expected) {
      Fail("an array has " + std::to_string(count) + " values where " + std::to_string(expected) + " were expected");
    }
    if (count > (data_.size() - position_) / sizeof(T)) Fail("an array is longer than the file");
    std::vector<T> values(count);
    const char* bytes = Take(count * sizeof(T));
    if (count > 0) std::memcpy(values.data(), bytes, count * sizeof(T));  // an empty vector's data() may be null
    return values;
  }
  std::string GetString() {
    const std::vector<char> bytes = GetVector<char>();
    return std::string(bytes.begin(), bytes.end());
  }
  // Throws unless the next bytes are `magic`.
  void ExpectMagic(const std::string& magic, const std::string& what) {
    if (data_.size() - position_ < magic.size() ||
        std::memcmp(data_.data() + position_, magic.data(), magic.size()) != 0) {
      throw std::runtime_error("'" + source_ + "' is not " + what);
    }
    position_ += magic.size();
  }
  bool AtEnd() const { return position_ == data_.size(); }
  [[noreturn]] void Fail(const std::string& why) const {
    throw std::runtime_error("'" + source_ + "' is damaged: " + why + " (at byte " + std::to_string(position_) + ")");
  }

 private:
  const char* Take(size_t bytes) {
    if (bytes > data_.size() - position_) Fail("it ends early");
    const char* start = data_.data() + position_;
    position_ += bytes;
    return start;
  }

  std::vector<char> data_;
  std::string source_;
  size_t position_ = 0;
};

}  // namespace p2n
