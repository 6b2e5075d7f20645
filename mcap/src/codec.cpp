#include "codec.hpp"

#include <lz4frame.h>
#include <zstd.h>

#include <array>

namespace haptel::mcap::detail {
namespace {

// Slicing-by-8 tables of the reflected polynomial 0xEDB88320.
struct CrcTables {
  std::array<std::array<uint32_t, 256>, 8> t{};
  CrcTables() {
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (uint32_t i = 0; i < 256; ++i) {
      for (size_t s = 1; s < 8; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFF];
    }
  }
};
const CrcTables kCrc;

}  // namespace

void Crc32::Update(const void* data, size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  uint32_t c = state_;
  const auto& t = kCrc.t;
  while (size >= 8) {
    uint32_t lo, hi;
    std::memcpy(&lo, p, 4);
    std::memcpy(&hi, p + 4, 4);
    lo ^= c;
    c = t[7][lo & 0xFF] ^ t[6][(lo >> 8) & 0xFF] ^ t[5][(lo >> 16) & 0xFF] ^ t[4][lo >> 24] ^
        t[3][hi & 0xFF] ^ t[2][(hi >> 8) & 0xFF] ^ t[1][(hi >> 16) & 0xFF] ^ t[0][hi >> 24];
    p += 8;
    size -= 8;
  }
  while (size-- > 0) c = t[0][(c ^ *p++) & 0xFF] ^ (c >> 8);
  state_ = c;
}

uint32_t Crc32Of(const void* data, size_t size) {
  Crc32 crc;
  crc.Update(data, size);
  return crc.value();
}

void Bytes::StringMap(const std::map<std::string, std::string>& map) {
  uint32_t length = 0;
  for (const auto& [k, v] : map) length += 8 + k.size() + v.size();
  U32(length);
  for (const auto& [k, v] : map) {
    String(k);
    String(v);
  }
}

void Bytes::U16U64Map(const std::map<uint16_t, uint64_t>& map) {
  U32(static_cast<uint32_t>(map.size() * 10));
  for (const auto& [k, v] : map) {
    U16(k);
    U64(v);
  }
}

const uint8_t* Cursor::Take(uint64_t n) {
  if (n > size_ - at_) {
    throw McapError(where_ + ": record ends " + std::to_string(n - (size_ - at_)) +
                    " bytes before the field at byte " + std::to_string(at_) +
                    " of its content (malformed record)");
  }
  const uint8_t* p = data_ + at_;
  at_ += n;
  return p;
}

std::map<std::string, std::string> Cursor::StringMap() {
  const uint32_t length = U32();
  Cursor inner(Take(length), length, where_);
  std::map<std::string, std::string> map;
  while (inner.remaining() > 0) {
    std::string key = inner.String();
    map[std::move(key)] = inner.String();
  }
  return map;
}

std::map<uint16_t, uint64_t> Cursor::U16U64Map() {
  const uint32_t length = U32();
  Cursor inner(Take(length), length, where_);
  std::map<uint16_t, uint64_t> map;
  while (inner.remaining() > 0) {
    const uint16_t key = inner.U16();
    map[key] = inner.U64();
  }
  return map;
}

struct Codec::Contexts {
  ZSTD_CCtx* zstd_c = nullptr;
  ZSTD_DCtx* zstd_d = nullptr;
  LZ4F_dctx* lz4_d = nullptr;
};

Codec::Codec() : contexts_(new Contexts) {}
Codec::~Codec() {
  ZSTD_freeCCtx(contexts_->zstd_c);
  ZSTD_freeDCtx(contexts_->zstd_d);
  if (contexts_->lz4_d != nullptr) LZ4F_freeDecompressionContext(contexts_->lz4_d);
  delete contexts_;
}

void Codec::Compress(Compression compression, int zstd_level, std::string_view in,
                     std::string& out) {
  switch (compression) {
    case Compression::kNone:
      out.assign(in);
      return;
    case Compression::kZstd: {
      if (contexts_->zstd_c == nullptr) contexts_->zstd_c = ZSTD_createCCtx();
      out.resize(ZSTD_compressBound(in.size()));
      const size_t n = ZSTD_compressCCtx(contexts_->zstd_c, out.data(), out.size(), in.data(),
                                         in.size(), zstd_level);
      if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
      out.resize(n);
      return;
    }
    case Compression::kLz4: {
      LZ4F_preferences_t preferences{};
      preferences.frameInfo.contentSize = in.size();
      out.resize(LZ4F_compressFrameBound(in.size(), &preferences));
      const size_t n =
          LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), &preferences);
      if (LZ4F_isError(n)) throw std::runtime_error(std::string("lz4: ") + LZ4F_getErrorName(n));
      out.resize(n);
      return;
    }
  }
}

void Codec::Decompress(Compression compression, const uint8_t* in, size_t in_size, uint64_t size,
                       std::string& out, const std::string& where) {
  out.resize(size);
  switch (compression) {
    case Compression::kNone:
      if (in_size != size) {
        throw McapError(where + ": an uncompressed chunk of " + std::to_string(in_size) +
                        " bytes says it holds " + std::to_string(size));
      }
      std::memcpy(out.data(), in, size);
      return;
    case Compression::kZstd: {
      if (contexts_->zstd_d == nullptr) contexts_->zstd_d = ZSTD_createDCtx();
      const size_t n = ZSTD_decompressDCtx(contexts_->zstd_d, out.data(), size, in, in_size);
      if (ZSTD_isError(n) || n != size) {
        throw McapError(
            where + ": zstd chunk does not decompress to its " + std::to_string(size) + " bytes" +
            (ZSTD_isError(n) ? std::string(" (") + ZSTD_getErrorName(n) + ")" : std::string()));
      }
      return;
    }
    case Compression::kLz4: {
      if (contexts_->lz4_d == nullptr) {
        if (LZ4F_isError(LZ4F_createDecompressionContext(&contexts_->lz4_d, LZ4F_VERSION))) {
          throw std::runtime_error("lz4: cannot create a decompression context");
        }
      }
      LZ4F_resetDecompressionContext(contexts_->lz4_d);
      size_t done_in = 0, done_out = 0;
      size_t hint = 1;
      while (hint != 0 && done_in < in_size) {
        size_t src = in_size - done_in, dst = size - done_out;
        hint = LZ4F_decompress(contexts_->lz4_d, out.data() + done_out, &dst, in + done_in, &src,
                               nullptr);
        if (LZ4F_isError(hint)) {
          throw McapError(where + ": lz4 chunk is corrupt (" + LZ4F_getErrorName(hint) + ")");
        }
        done_in += src;
        done_out += dst;
        if (src == 0 && dst == 0) break;
      }
      if (hint != 0 || done_out != size) {
        throw McapError(where + ": lz4 chunk does not decompress to its " + std::to_string(size) +
                        " bytes (got " + std::to_string(done_out) + ")");
      }
      return;
    }
  }
}

Compression CompressionFromField(std::string_view field, const std::string& where) {
  if (field.empty()) return Compression::kNone;
  if (field == "zstd") return Compression::kZstd;
  if (field == "lz4") return Compression::kLz4;
  throw McapError(where + ": unknown chunk compression '" + std::string(field) +
                  "' (expected zstd, lz4 or none)");
}

}  // namespace haptel::mcap::detail
