#include "haptel/mcap/reader.hpp"

namespace haptel::mcap {
// Stub: the contract, committed first; the body follows.
struct Reader::Impl {
  std::filesystem::path path;
  Summary summary;
  std::string profile, library;
  Loss loss;
};
Reader Reader::Open(const std::filesystem::path& path) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  return Reader(std::move(impl));
}
Reader::Reader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Reader::~Reader() = default;
Reader::Reader(Reader&&) noexcept = default;
Reader& Reader::operator=(Reader&&) noexcept = default;
const std::filesystem::path& Reader::path() const { return impl_->path; }
const Summary& Reader::summary() const { return impl_->summary; }
const std::map<uint16_t, Channel>& Reader::channels() const { return impl_->summary.channels; }
const std::map<uint16_t, Schema>& Reader::schemas() const { return impl_->summary.schemas; }
const Statistics& Reader::statistics() const { return impl_->summary.statistics; }
const std::string& Reader::profile() const { return impl_->profile; }
const std::string& Reader::library() const { return impl_->library; }
bool Reader::recovered() const { return impl_->loss.truncated; }
const Loss& Reader::loss() const { return impl_->loss; }
void Reader::ForEachMessage(uint64_t, uint64_t, const std::vector<std::string>&,
                            const std::function<void(const MessageView&)>&) const {}
Attachment Reader::ReadAttachment(const AttachmentIndex&) const { return {}; }
Metadata Reader::ReadMetadata(const MetadataIndex&) const { return {}; }
std::vector<std::string> Reader::Verify() const { return {}; }
}  // namespace haptel::mcap
