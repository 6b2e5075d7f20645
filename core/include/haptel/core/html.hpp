#pragma once
/// @file Text for HTML pages the programs write (the study's report and
/// console): everything from a file, a database or a form is escaped.
#include <string>
#include <string_view>

namespace haptel {

/// `text` with & < > " ' as character references: safe in element content
/// and in quoted attribute values.
std::string HtmlEscape(std::string_view text);

}  // namespace haptel
