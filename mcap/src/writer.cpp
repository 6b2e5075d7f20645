#include "haptel/mcap/writer.hpp"

namespace haptel::mcap {
// Stub: the contract, committed first; the body follows.
struct Writer::Impl {
  std::filesystem::path path;
  Statistics statistics;
};
Writer::Writer(const std::filesystem::path& path, WriterOptions) : impl_(new Impl{path, {}}) {}
Writer::~Writer() = default;
uint16_t Writer::AddSchema(std::string, std::string, std::string) { return 1; }
uint16_t Writer::AddChannel(uint16_t, std::string, std::string,
                            std::map<std::string, std::string>) {
  return 0;
}
void Writer::Write(uint16_t, uint32_t, uint64_t, uint64_t, const void*, size_t) {}
void Writer::AddAttachment(std::string, std::string, uint64_t, const void*, size_t) {}
void Writer::AddMetadata(std::string, std::map<std::string, std::string>) {}
void Writer::Flush() {}
void Writer::Close() {}
const std::filesystem::path& Writer::path() const { return impl_->path; }
uint64_t Writer::bytes_written() const { return 0; }
const Statistics& Writer::statistics() const { return impl_->statistics; }
}  // namespace haptel::mcap
