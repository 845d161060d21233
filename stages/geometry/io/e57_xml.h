// A small, strict XML parser for the XML section of E57 files (ASTM E2807).
//
// E57 XML uses a narrow subset of XML 1.0: an optional declaration, comments,
// elements with attributes, character data and CDATA sections (strings). This
// parser builds a DOM of that subset and rejects anything else with a 1-based
// line number:
//   - the five predefined entities (&lt; &gt; &amp; &quot; &apos;) and
//     character references (&#65; &#x41;) are decoded, other entities rejected;
//   - a DOCTYPE without an internal subset is skipped, one with a subset is
//     rejected (no entity declarations, so no expansion bombs);
//   - namespaces are kept as written: an element `nor:normalX` has the name
//     "nor:normalX" and Prefix() "nor"; E57 standard elements are unprefixed
//     (default namespace), extensions carry a prefix;
//   - nesting deeper than kMaxXmlDepth is rejected (bounded recursion).
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "base/status.h"

namespace pb::e57 {

inline constexpr int kMaxXmlDepth = 128;

struct XmlElement {
  std::string name;  // qualified name as written, e.g. "cartesianX", "nor:normalX"
  std::vector<std::pair<std::string, std::string>> attributes;  // decoded values, in order
  std::string text;  // character data and CDATA of this element only, decoded
  std::vector<XmlElement> children;
  int line = 0;  // 1-based line of the start tag

  // First child with this exact qualified name, or nullptr.
  const XmlElement* Child(std::string_view child_name) const;
  // Attribute value, or nullptr.
  const std::string* Attribute(std::string_view attribute_name) const;
  // "nor" for "nor:normalX", "" for unprefixed names.
  std::string_view Prefix() const;
};

// Parses a whole document and returns its root element. Errors read
// "line N: what was expected" (the caller prefixes the file name).
Expected<XmlElement> ParseXml(std::string_view document);

}  // namespace pb::e57
