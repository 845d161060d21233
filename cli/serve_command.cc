#include "cli/serve_command.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <thread>
#include <vector>

namespace pb {
namespace {

constexpr const char* kUsage =
    "Usage: pointbake serve [DIR] [--port N]\n"
    "\n"
    "Serves DIR (default: the current folder; e.g. out/demo, a campaign's --out)\n"
    "over HTTP on 127.0.0.1 only and prints its URL, so a browser can open the\n"
    "3-D viewer of the report (report/viewer/index.html) and load the models.\n"
    "Serves until interrupted (Ctrl-C).\n"
    "\n"
    "Options:\n"
    "  --port N     TCP port (default 8173; 0 picks a free one)\n"
    "  -h, --help   this text\n"
    "\n"
    "A headset: WebXR needs https or localhost, and this server listens on the\n"
    "loopback only; over USB, `adb reverse tcp:8173 tcp:8173` makes the URL\n"
    "work in the headset's browser (docs/viewer.md).\n";

constexpr size_t kMaxRequestBytes = 16384;

int Usage(const std::string& problem) {
  std::fprintf(stderr, "pointbake serve: %s\n\n%s", problem.c_str(), kUsage);
  return 2;
}

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool WriteAll(int fd, const char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = ::send(fd, data, size, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= size_t(n);
  }
  return true;
}

void SendStatus(int client, int code, const char* reason, const std::string& body) {
  const std::string response = "HTTP/1.1 " + std::to_string(code) + " " + reason +
                               "\r\nContent-Type: text/plain; charset=utf-8\r\nContent-Length: " +
                               std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" + body;
  WriteAll(client, response.data(), response.size());
}

}  // namespace

Expected<std::filesystem::path> ResolveStaticPath(const std::filesystem::path& root,
                                                  const std::string& target) {
  std::string raw = target.substr(0, target.find_first_of("?#"));
  if (raw.empty() || raw[0] != '/') return Status::Invalid("request target must start with '/': " + target);
  std::string decoded;
  for (size_t i = 0; i < raw.size(); ++i) {
    if (raw[i] == '%') {
      const int hi = i + 2 < raw.size() ? HexValue(raw[i + 1]) : -1;
      const int lo = i + 2 < raw.size() ? HexValue(raw[i + 2]) : -1;
      if (hi < 0 || lo < 0) return Status::Invalid("bad percent escape in " + target);
      decoded.push_back(char(hi * 16 + lo));
      i += 2;
    } else {
      decoded.push_back(raw[i]);
    }
  }
  if (decoded.find('\0') != std::string::npos) return Status::Invalid("NUL in " + target);
  std::filesystem::path relative;
  size_t start = 1;
  while (start <= decoded.size()) {
    const size_t end = std::min(decoded.find('/', start), decoded.size());
    const std::string segment = decoded.substr(start, end - start);
    if (segment == "..") return Status::Invalid("'..' in " + target);
    if (!segment.empty() && segment != ".") relative /= segment;
    start = end + 1;
  }
  std::error_code ec;
  const std::filesystem::path canonical_root = std::filesystem::canonical(root, ec);
  if (ec) return Status::NotFound(root.string() + ": " + ec.message());
  std::filesystem::path file = canonical_root / relative;
  if (std::filesystem::is_directory(file, ec)) file /= "index.html";
  const std::filesystem::path canonical = std::filesystem::canonical(file, ec);
  if (ec || !std::filesystem::is_regular_file(canonical)) return Status::NotFound(target + ": not found");
  // Symlinks may not lead out of the root.
  const std::string root_text = canonical_root.string() + "/";
  if (canonical.string().compare(0, root_text.size(), root_text) != 0) {
    return Status::Invalid(target + ": outside the served folder");
  }
  return canonical;
}

std::string ContentTypeFor(const std::filesystem::path& file) {
  static const std::map<std::string, std::string> kTypes = {
      {".html", "text/html; charset=utf-8"}, {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"}, {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},         {".glb", "model/gltf-binary"},
      {".gltf", "model/gltf+json"},           {".png", "image/png"},
      {".jpg", "image/jpeg"},                 {".svg", "image/svg+xml"},
      {".wasm", "application/wasm"},         {".ktx2", "image/ktx2"},
      {".csv", "text/csv; charset=utf-8"},   {".md", "text/markdown; charset=utf-8"},
      {".txt", "text/plain; charset=utf-8"}, {".ply", "application/octet-stream"}};
  std::string extension = file.extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  const auto it = kTypes.find(extension);
  return it == kTypes.end() ? "application/octet-stream" : it->second;
}

Expected<int> ListenLoopback(uint16_t port, uint16_t* bound_port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return Status::Errno("socket", "socket");
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(port);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0 || ::listen(fd, 64) != 0) {
    const Status status = Status::Io("127.0.0.1:" + std::to_string(port) + ": " + std::strerror(errno));
    ::close(fd);
    return status;
  }
  socklen_t length = sizeof(address);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  *bound_port = ntohs(address.sin_port);
  return fd;
}

void ServeOneRequest(int client, const std::filesystem::path& root) {
  timeval timeout{10, 0};
  ::setsockopt(client, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
  ::setsockopt(client, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof(timeout));
  std::string request;
  char buffer[4096];
  while (request.find("\r\n\r\n") == std::string::npos && request.size() < kMaxRequestBytes) {
    const ssize_t n = ::recv(client, buffer, sizeof(buffer), 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    request.append(buffer, size_t(n));
  }
  const size_t line_end = request.find("\r\n");
  const std::string line = request.substr(0, line_end);
  const size_t space1 = line.find(' '), space2 = line.rfind(' ');
  if (line_end == std::string::npos || space1 == std::string::npos || space2 <= space1) {
    SendStatus(client, 400, "Bad Request", "bad request\n");
  } else {
    const std::string method = line.substr(0, space1);
    const std::string target = line.substr(space1 + 1, space2 - space1 - 1);
    if (method != "GET" && method != "HEAD") {
      SendStatus(client, 405, "Method Not Allowed", "only GET and HEAD\n");
    } else if (Expected<std::filesystem::path> file = ResolveStaticPath(root, target); !file.ok()) {
      const bool missing = file.status().code() == Status::Code::kNotFound;
      SendStatus(client, missing ? 404 : 403, missing ? "Not Found" : "Forbidden",
                 file.status().message() + "\n");
    } else {
      std::ifstream in(*file, std::ios::binary);
      std::error_code ec;
      const uintmax_t size = std::filesystem::file_size(*file, ec);
      if (!in || ec) {
        SendStatus(client, 500, "Internal Server Error", "cannot read " + target + "\n");
      } else {
        // no-store: a campaign run again rewrites the models under the same names.
        const std::string header = "HTTP/1.1 200 OK\r\nContent-Type: " + ContentTypeFor(*file) +
                                   "\r\nContent-Length: " + std::to_string(size) +
                                   "\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n";
        bool ok = WriteAll(client, header.data(), header.size());
        std::vector<char> chunk(1 << 16);
        while (ok && method == "GET" && in) {
          in.read(chunk.data(), std::streamsize(chunk.size()));
          if (in.gcount() > 0) ok = WriteAll(client, chunk.data(), size_t(in.gcount()));
        }
      }
    }
  }
  ::shutdown(client, SHUT_WR);
  ::close(client);
}

namespace {

int RunServe(const std::vector<std::string>& args) {
  std::string dir;
  int port = 8173;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (a == "--port") {
      if (i + 1 >= args.size()) return Usage("--port needs a value");
      const std::string& value = args[++i];
      const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), port);
      if (ec != std::errc() || end != value.data() + value.size() || port < 0 || port > 65535) {
        return Usage("--port: expected 0 to 65535, got '" + value + "'");
      }
    } else if (!a.empty() && a[0] == '-') {
      return Usage("unknown option " + a);
    } else if (dir.empty()) {
      dir = a;
    } else {
      return Usage("one folder only (got '" + dir + "' and '" + a + "')");
    }
  }
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    std::fprintf(stderr, "pointbake serve: %s: not a folder\n", dir.c_str());
    return 2;
  }
  const std::filesystem::path root = std::filesystem::canonical(dir, ec);
  uint16_t bound = 0;
  Expected<int> listener = ListenLoopback(uint16_t(port), &bound);
  if (!listener.ok()) {
    std::fprintf(stderr, "pointbake serve: %s\n", listener.status().message().c_str());
    return 2;
  }
  const std::string url = "http://127.0.0.1:" + std::to_string(bound) + "/";
  std::printf("serving %s at %s\n", root.c_str(), url.c_str());
  if (std::filesystem::exists(root / "report" / "viewer" / "index.html")) {
    std::printf("viewer: %sreport/viewer/index.html\n", url.c_str());
  }
  if (std::filesystem::exists(root / "report" / "report.html")) {
    std::printf("report: %sreport/report.html\n", url.c_str());
  }
  std::fflush(stdout);
  std::signal(SIGPIPE, SIG_IGN);
  for (;;) {
    const int client = ::accept4(*listener, nullptr, nullptr, SOCK_CLOEXEC);
    if (client < 0) {
      if (errno == EINTR || errno == ECONNABORTED || errno == EMFILE || errno == ENFILE) continue;
      std::fprintf(stderr, "pointbake serve: accept: %s\n", std::strerror(errno));
      return 2;
    }
    std::thread(ServeOneRequest, client, root).detach();
  }
}

}  // namespace

CliCommand ServeCommand() {
  return {"serve", "Serve a campaign folder on 127.0.0.1 for the 3-D viewer (report/viewer/)",
          &RunServe};
}

}  // namespace pb
