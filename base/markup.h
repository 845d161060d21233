// Text for XML and HTML (the report's pages, VTK's .vtp files).
#pragma once

#include <string>
#include <string_view>

namespace pb {

// `text` with & < > " ' as character references, safe in element content and
// in single- or double-quoted attribute values of XML and HTML.
std::string EscapeMarkup(std::string_view text);

}  // namespace pb
