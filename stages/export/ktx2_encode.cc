#include "stages/export/ktx2_encode.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

extern char** environ;

namespace pb {
namespace {

std::string ToolsDir() {
  if (const char* dir = std::getenv("POINTBAKE_TOOLS_DIR"); dir && *dir) return dir;
  return PB_TOOLS_DIR;
}

std::vector<uint8_t> ToRgba(const Image& image) {
  const size_t texels = size_t(image.width) * size_t(image.height);
  std::vector<uint8_t> rgba(4 * texels, 255);
  const uint8_t* in = image.u8();
  const int c = image.channels;
  for (size_t t = 0; t < texels; ++t) {
    const uint8_t* p = in + t * c;
    if (c <= 2) {
      rgba[4 * t] = rgba[4 * t + 1] = rgba[4 * t + 2] = p[0];
      if (c == 2) rgba[4 * t + 3] = p[1];
    } else {
      for (int k = 0; k < c; ++k) rgba[4 * t + k] = p[k];
    }
  }
  return rgba;
}

std::string ReadAll(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Removes the scratch folder however EncodeKtx2 returns.
struct ScratchDir {
  std::filesystem::path path;
  ~ScratchDir() {
    std::error_code ignored;
    if (!path.empty()) std::filesystem::remove_all(path, ignored);
  }
};

// The npm package (folder in tools/node_modules) that encodes `texels`.
std::string EncoderPackage(int64_t texels) {
  return texels > kKtx2CurrentEncoderMaxTexels ? "ktx2-encoder-legacy" : "ktx2-encoder";
}

}  // namespace

std::string Ktx2EncoderVersion(int64_t texels) {
  const std::string text =
      ReadAll(std::filesystem::path(ToolsDir()) / "node_modules" / EncoderPackage(texels) / "package.json");
  const nlohmann::json package = nlohmann::json::parse(text, nullptr, false);
  if (!package.is_object() || !package.contains("version")) return "";
  return "ktx2-encoder " + package["version"].get<std::string>();
}

Expected<std::vector<uint8_t>> EncodeKtx2(const Image& image, Ktx2Mode mode, const std::string& what,
                                          std::string* encoder) {
  const std::string context = what + ": KTX2 encoding";
  if (image.type != Image::PixelType::kU8 || image.channels < 1 || image.channels > 4 ||
      image.width <= 0 || image.height <= 0) {
    return Status::Invalid(context + ": expected an 8-bit image with 1 to 4 channels");
  }
  const std::filesystem::path tools = ToolsDir();
  const std::filesystem::path script = tools / "encode_ktx2.mjs";
  const int64_t texels = int64_t{image.width} * image.height;
  const std::string package = EncoderPackage(texels);
  if (!std::filesystem::exists(script) || !std::filesystem::exists(tools / "node_modules" / package)) {
    return Status::NotFound(context + " needs " + script.string() + " and its npm packages (" +
                            package + ") in " + (tools / "node_modules").string() +
                            " (npm ci --prefix tools; or set POINTBAKE_TOOLS_DIR)");
  }
  ScratchDir scratch;
  {
    std::string pattern = (std::filesystem::temp_directory_path() / "pointbake-ktx2-XXXXXX").string();
    if (!mkdtemp(pattern.data())) return Status::Errno(pattern, "mkdtemp").WithContext(context);
    scratch.path = pattern;
  }
  const std::filesystem::path input = scratch.path / "in.rgba", output = scratch.path / "out.ktx2",
                              log = scratch.path / "encoder.log";
  {
    const std::vector<uint8_t> rgba = ToRgba(image);
    std::ofstream out(input, std::ios::binary);
    out.write(reinterpret_cast<const char*>(rgba.data()), std::streamsize(rgba.size()));
    if (!out.flush()) return Status::Errno(input.string(), "write").WithContext(context);
  }
  std::vector<std::string> args = {"node",
                                   script.string(),
                                   mode == Ktx2Mode::kEtc1sSrgb ? "etc1s" : "uastc",
                                   mode == Ktx2Mode::kEtc1sSrgb ? "srgb" : "linear",
                                   std::to_string(image.width),
                                   std::to_string(image.height),
                                   input.string(),
                                   output.string(),
                                   package};
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  // The encoder's progress goes to stdout, its errors to stderr: both to the
  // log, which the error message quotes.
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, "node", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    return Status::NotFound(context + ": cannot run node (Node.js): " + std::strerror(spawned));
  }
  int wait_status = 0;
  while (waitpid(pid, &wait_status, 0) < 0) {
    if (errno != EINTR) return Status::Errno("node", "waitpid").WithContext(context);
  }
  if (!WIFEXITED(wait_status) || WEXITSTATUS(wait_status) != 0) {
    std::string message = ReadAll(log);
    if (message.size() > 2000) message = "..." + message.substr(message.size() - 2000);
    return Status::Internal(context + ": " + script.string() + " failed (" +
                            (WIFEXITED(wait_status) ? "exit " + std::to_string(WEXITSTATUS(wait_status))
                                                    : "killed by signal " + std::to_string(WTERMSIG(wait_status))) +
                            "): " + message);
  }
  if (encoder) *encoder = Ktx2EncoderVersion(texels);
  const std::string bytes = ReadAll(output);
  return std::vector<uint8_t>(bytes.begin(), bytes.end());
}

}  // namespace pb
