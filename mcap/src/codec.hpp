#pragma once
// The MCAP byte layer shared by the writer and the reader (private to mcap/):
// little-endian fields, prefixed strings and maps, the CRC-32 the
// specification uses (zlib's), and the chunk compressions.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <string_view>

#include "haptel/mcap/records.hpp"

namespace haptel::mcap::detail {

inline constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
inline constexpr size_t kRecordPrefix = 1 + 8;  // opcode, content length
inline constexpr size_t kFooterContent = 8 + 8 + 4;
inline constexpr size_t kFooterRecord = kRecordPrefix + kFooterContent;

/// CRC-32 (ISO-HDLC, zlib's), updated piecewise.
class Crc32 {
 public:
  void Update(const void* data, size_t size);
  void Update(std::string_view bytes) { Update(bytes.data(), bytes.size()); }
  uint32_t value() const { return state_ ^ 0xFFFFFFFFu; }

 private:
  uint32_t state_ = 0xFFFFFFFFu;
};
uint32_t Crc32Of(const void* data, size_t size);

/// Appends little-endian fields to a byte string.
class Bytes {
 public:
  explicit Bytes(std::string& out) : out_(out) {}
  void U8(uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void U16(uint16_t v) { Raw(&v, 2); }
  void U32(uint32_t v) { Raw(&v, 4); }
  void U64(uint64_t v) { Raw(&v, 8); }
  void Raw(const void* data, size_t size) {
    out_.append(static_cast<const char*>(data), size);  // x86-64 and ARM64: little-endian
  }
  void String(std::string_view s) {
    U32(static_cast<uint32_t>(s.size()));
    Raw(s.data(), s.size());
  }
  void StringMap(const std::map<std::string, std::string>& map);
  void U16U64Map(const std::map<uint16_t, uint64_t>& map);
  /// Starts a record: its opcode and a length patched by End.
  size_t Begin(Opcode opcode) {
    U8(static_cast<uint8_t>(opcode));
    const size_t at = out_.size();
    U64(0);
    return at;
  }
  void End(size_t length_at) {
    const uint64_t length = out_.size() - length_at - 8;
    std::memcpy(out_.data() + length_at, &length, 8);
  }

 private:
  std::string& out_;
};

/// Reads little-endian fields from a record's content; running past its end
/// throws McapError naming `where` (the file and the record's offset).
class Cursor {
 public:
  Cursor(const uint8_t* data, size_t size, const std::string& where)
      : data_(data), size_(size), where_(where) {}
  uint8_t U8() { return Fixed<uint8_t>(); }
  uint16_t U16() { return Fixed<uint16_t>(); }
  uint32_t U32() { return Fixed<uint32_t>(); }
  uint64_t U64() { return Fixed<uint64_t>(); }
  std::string String() {
    const uint32_t n = U32();
    return std::string(reinterpret_cast<const char*>(Take(n)), n);
  }
  std::map<std::string, std::string> StringMap();
  std::map<uint16_t, uint64_t> U16U64Map();
  const uint8_t* Take(uint64_t n);
  size_t remaining() const { return size_ - at_; }
  size_t at() const { return at_; }

 private:
  template <class T>
  T Fixed() {
    T v;
    std::memcpy(&v, Take(sizeof(T)), sizeof(T));
    return v;
  }
  const uint8_t* data_;
  size_t size_;
  size_t at_ = 0;
  const std::string& where_;
};

/// Chunk compression with reusable contexts (one per writer or reader).
class Codec {
 public:
  Codec();
  ~Codec();
  Codec(const Codec&) = delete;
  Codec& operator=(const Codec&) = delete;
  /// `out` = `in` compressed (replaced).
  void Compress(Compression compression, int zstd_level, std::string_view in, std::string& out);
  /// `out` = `in` decompressed, which must give exactly `size` bytes;
  /// otherwise McapError naming `where`.
  void Decompress(Compression compression, const uint8_t* in, size_t in_size, uint64_t size,
                  std::string& out, const std::string& where);

 private:
  struct Contexts;
  Contexts* contexts_;
};

/// The chunk's compression field as the enum; an unknown one is McapError.
Compression CompressionFromField(std::string_view field, const std::string& where);

}  // namespace haptel::mcap::detail
