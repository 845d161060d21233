// XML 1.0 subset parser for E57 (see e57_xml.h). Reference: W3C XML 1.0
// (Fifth Edition), sections 2.4 (character data), 2.5 (comments), 2.7 (CDATA),
// 3.1 (tags), 4.1 (character and entity references). Departures: no DTD
// processing, no encoding other than UTF-8/ASCII, names are checked only for
// the ASCII characters XML forbids.
#include "stages/geometry/io/e57_xml.h"

#include <cstdint>

namespace pb::e57 {

const XmlElement* XmlElement::Child(std::string_view child_name) const {
  for (const XmlElement& child : children) {
    if (child.name == child_name) return &child;
  }
  return nullptr;
}

const std::string* XmlElement::Attribute(std::string_view attribute_name) const {
  for (const auto& [key, value] : attributes) {
    if (key == attribute_name) return &value;
  }
  return nullptr;
}

std::string_view XmlElement::Prefix() const {
  const size_t colon = name.find(':');
  return colon == std::string::npos ? std::string_view() : std::string_view(name).substr(0, colon);
}

namespace {

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

bool IsNameStart(char c) {
  const auto u = static_cast<unsigned char>(c);
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || c == ':' || u >= 0x80;
}

bool IsNameChar(char c) { return IsNameStart(c) || (c >= '0' && c <= '9') || c == '-' || c == '.'; }

void AppendUtf8(uint32_t code_point, std::string* out) {
  if (code_point < 0x80) {
    out->push_back(static_cast<char>(code_point));
  } else if (code_point < 0x800) {
    out->push_back(static_cast<char>(0xC0 | (code_point >> 6)));
    out->push_back(static_cast<char>(0x80 | (code_point & 0x3F)));
  } else if (code_point < 0x10000) {
    out->push_back(static_cast<char>(0xE0 | (code_point >> 12)));
    out->push_back(static_cast<char>(0x80 | ((code_point >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (code_point & 0x3F)));
  } else {
    out->push_back(static_cast<char>(0xF0 | (code_point >> 18)));
    out->push_back(static_cast<char>(0x80 | ((code_point >> 12) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | ((code_point >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (code_point & 0x3F)));
  }
}

class Parser {
 public:
  explicit Parser(std::string_view doc) : doc_(doc) {}

  Expected<XmlElement> Document() {
    if (doc_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = 3;  // UTF-8 byte order mark
    PB_RETURN_IF_ERROR(Misc(/*allow_doctype=*/true));
    if (AtEnd() || Peek() != '<') return Error("expected the root element");
    XmlElement root;
    PB_RETURN_IF_ERROR(Element(&root, 1));
    PB_RETURN_IF_ERROR(Misc(/*allow_doctype=*/false));
    if (!AtEnd()) return Error("unexpected content after the root element");
    return root;
  }

 private:
  bool AtEnd() const { return pos_ >= doc_.size(); }
  char Peek() const { return doc_[pos_]; }
  bool StartsWith(std::string_view s) const { return doc_.substr(pos_, s.size()) == s; }

  void Advance(size_t n) {
    for (size_t i = 0; i < n && pos_ < doc_.size(); ++i, ++pos_) {
      if (doc_[pos_] == '\n') ++line_;
    }
  }
  void SkipSpace() {
    while (!AtEnd() && IsSpace(Peek())) Advance(1);
  }

  Status Error(const std::string& what) const {
    return Status::Corrupt("line " + std::to_string(line_) + ": " + what);
  }

  // Skips to just past `terminator`; error naming `construct` if absent.
  Status SkipPast(std::string_view terminator, const char* construct) {
    const size_t end = doc_.find(terminator, pos_);
    if (end == std::string_view::npos) return Error(std::string("unterminated ") + construct);
    Advance(end + terminator.size() - pos_);
    return Status::Ok();
  }

  // Whitespace, comments and processing instructions outside the root.
  Status Misc(bool allow_doctype) {
    while (true) {
      SkipSpace();
      if (StartsWith("<?")) {
        PB_RETURN_IF_ERROR(SkipPast("?>", "processing instruction"));
      } else if (StartsWith("<!--")) {
        PB_RETURN_IF_ERROR(SkipPast("-->", "comment"));
      } else if (allow_doctype && StartsWith("<!DOCTYPE")) {
        const size_t end = doc_.find('>', pos_);
        const size_t subset = doc_.find('[', pos_);
        if (subset != std::string_view::npos && (end == std::string_view::npos || subset < end)) {
          return Error("DOCTYPE with an internal subset is not supported");
        }
        PB_RETURN_IF_ERROR(SkipPast(">", "DOCTYPE"));
      } else {
        return Status::Ok();
      }
    }
  }

  Status Name(std::string* out) {
    if (AtEnd() || !IsNameStart(Peek())) return Error("expected a name");
    const size_t start = pos_;
    while (!AtEnd() && IsNameChar(Peek())) ++pos_;  // names hold no newline
    out->assign(doc_.substr(start, pos_ - start));
    return Status::Ok();
  }

  // At '&': decodes one reference into `out`.
  Status Reference(std::string* out) {
    const size_t semicolon = doc_.find(';', pos_);
    if (semicolon == std::string_view::npos || semicolon - pos_ > 12) {
      return Error("'&' must start an entity reference such as &amp;");
    }
    const std::string_view entity = doc_.substr(pos_ + 1, semicolon - pos_ - 1);
    if (entity == "lt") {
      out->push_back('<');
    } else if (entity == "gt") {
      out->push_back('>');
    } else if (entity == "amp") {
      out->push_back('&');
    } else if (entity == "quot") {
      out->push_back('"');
    } else if (entity == "apos") {
      out->push_back('\'');
    } else if (entity.size() >= 2 && entity[0] == '#') {
      const bool hex = entity[1] == 'x';
      const std::string_view digits = entity.substr(hex ? 2 : 1);
      if (digits.empty()) return Error("empty character reference");
      uint32_t code_point = 0;
      for (char c : digits) {
        uint32_t digit;
        if (c >= '0' && c <= '9') {
          digit = static_cast<uint32_t>(c - '0');
        } else if (hex && c >= 'a' && c <= 'f') {
          digit = static_cast<uint32_t>(c - 'a' + 10);
        } else if (hex && c >= 'A' && c <= 'F') {
          digit = static_cast<uint32_t>(c - 'A' + 10);
        } else {
          return Error("bad character reference '&" + std::string(entity) + ";'");
        }
        code_point = code_point * (hex ? 16 : 10) + digit;
        if (code_point > 0x10FFFF) return Error("character reference out of range");
      }
      if (code_point == 0) return Error("character reference to NUL");
      AppendUtf8(code_point, out);
    } else {
      return Error("unknown entity '&" + std::string(entity) + ";'");
    }
    Advance(semicolon + 1 - pos_);
    return Status::Ok();
  }

  Status AttributeValue(std::string* out) {
    if (AtEnd() || (Peek() != '"' && Peek() != '\''))
      return Error("expected a quoted attribute value");
    const char quote = Peek();
    Advance(1);
    while (true) {
      if (AtEnd()) return Error("unterminated attribute value");
      const char c = Peek();
      if (c == quote) break;
      if (c == '<') return Error("'<' inside an attribute value");
      if (c == '&') {
        PB_RETURN_IF_ERROR(Reference(out));
      } else {
        out->push_back(c);
        Advance(1);
      }
    }
    Advance(1);
    return Status::Ok();
  }

  // At '<' of a start tag.
  Status Element(XmlElement* element, int depth) {
    if (depth > kMaxXmlDepth)
      return Error("elements nested deeper than " + std::to_string(kMaxXmlDepth));
    element->line = line_;
    Advance(1);
    PB_RETURN_IF_ERROR(Name(&element->name));
    while (true) {
      const size_t before = pos_;
      SkipSpace();
      if (AtEnd()) return Error("unterminated start tag <" + element->name + ">");
      if (StartsWith("/>")) {
        Advance(2);
        return Status::Ok();
      }
      if (Peek() == '>') {
        Advance(1);
        break;
      }
      if (pos_ == before)
        return Error("expected whitespace, '>' or '/>' in <" + element->name + ">");
      std::string key, value;
      PB_RETURN_IF_ERROR(Name(&key));
      SkipSpace();
      if (AtEnd() || Peek() != '=') return Error("expected '=' after attribute '" + key + "'");
      Advance(1);
      SkipSpace();
      PB_RETURN_IF_ERROR(AttributeValue(&value));
      if (element->Attribute(key) != nullptr) return Error("duplicate attribute '" + key + "'");
      element->attributes.emplace_back(std::move(key), std::move(value));
    }
    // Content.
    while (true) {
      if (AtEnd()) return Error("missing end tag </" + element->name + ">");
      const char c = Peek();
      if (c == '&') {
        PB_RETURN_IF_ERROR(Reference(&element->text));
      } else if (c != '<') {
        element->text.push_back(c);
        Advance(1);
      } else if (StartsWith("</")) {
        Advance(2);
        std::string end_name;
        PB_RETURN_IF_ERROR(Name(&end_name));
        if (end_name != element->name) {
          return Error("end tag </" + end_name + "> does not match <" + element->name + ">");
        }
        SkipSpace();
        if (AtEnd() || Peek() != '>') return Error("expected '>' to close </" + end_name);
        Advance(1);
        return Status::Ok();
      } else if (StartsWith("<![CDATA[")) {
        Advance(9);
        const size_t end = doc_.find("]]>", pos_);
        if (end == std::string_view::npos) return Error("unterminated CDATA section");
        element->text.append(doc_.substr(pos_, end - pos_));
        Advance(end + 3 - pos_);
      } else if (StartsWith("<!--")) {
        PB_RETURN_IF_ERROR(SkipPast("-->", "comment"));
      } else if (StartsWith("<?")) {
        PB_RETURN_IF_ERROR(SkipPast("?>", "processing instruction"));
      } else if (StartsWith("<!")) {
        return Error("unexpected markup declaration inside <" + element->name + ">");
      } else {
        element->children.emplace_back();
        PB_RETURN_IF_ERROR(Element(&element->children.back(), depth + 1));
      }
    }
  }

  std::string_view doc_;
  size_t pos_ = 0;
  int line_ = 1;
};

}  // namespace

Expected<XmlElement> ParseXml(std::string_view document) { return Parser(document).Document(); }

}  // namespace pb::e57
