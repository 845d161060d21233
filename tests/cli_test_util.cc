#include "tests/cli_test_util.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <chrono>
#include <algorithm>

extern char** environ;

namespace pbtest {
namespace fs = std::filesystem;

const char* Binary() { return PB_BINARY; }
const char* TestPlugin() { return PB_TEST_PLUGIN; }
const char* HelloPlugin() { return PB_HELLO_PLUGIN; }
std::string SourceDir() { return PB_SOURCE_DIR_STR; }

std::string RunResult::Describe() const {
  std::ostringstream s;
  s << "command: " << command << "\nexit: " << exit_code << (signaled ? " (signal)" : "")
    << "\n--- stdout ---\n" << out << "--- stderr ---\n" << err;
  return s.str();
}

void RemoveAll(const std::string& path) {
  ::pb::testing::TempDir::RemoveAll(path);
}

namespace {

std::string Quote(const std::string& s) {
  if (!s.empty() && s.find_first_of(" \t\n'\"\\$`*?[]{}();&|<>") == std::string::npos) return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

struct ExecData {
  std::vector<std::string> argv_s;
  std::vector<std::string> env_s;
  std::vector<char*> argv;
  std::vector<char*> envp;
};

ExecData Prepare(const std::vector<std::string>& args, const EnvExtras& env) {
  ExecData d;
  d.argv_s.push_back(Binary());
  d.argv_s.insert(d.argv_s.end(), args.begin(), args.end());
  for (char** e = environ; *e; ++e) {
    std::string kv = *e;
    bool overridden = false;
    for (const auto& [k, v] : env)
      if (kv.rfind(k + "=", 0) == 0) overridden = true;
    if (!overridden) d.env_s.push_back(kv);
  }
  for (const auto& [k, v] : env) d.env_s.push_back(k + "=" + v);
  for (auto& s : d.argv_s) d.argv.push_back(s.data());
  d.argv.push_back(nullptr);
  for (auto& s : d.env_s) d.envp.push_back(s.data());
  d.envp.push_back(nullptr);
  return d;
}

int OpenOut(const std::string& file) {
  return ::open(file.empty() ? "/dev/null" : file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
}

// In the child: never returns.
[[noreturn]] void ExecChild(ExecData& d, int out_fd, int err_fd, const std::string& cwd, bool own_group) {
  if (own_group) ::setpgid(0, 0);
  const int in_fd = ::open("/dev/null", O_RDONLY);
  ::dup2(in_fd, 0);
  ::dup2(out_fd, 1);
  ::dup2(err_fd, 2);
  if (!cwd.empty() && ::chdir(cwd.c_str()) != 0) ::_exit(126);
  ::execve(d.argv[0], d.argv.data(), d.envp.data());
  ::_exit(127);
}

}  // namespace

int Wait(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

int WaitWithTimeout(pid_t pid, double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < deadline) {
    int status = 0;
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) {
      if (WIFEXITED(status)) return WEXITSTATUS(status);
      if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
      return -1;
    }
    if (r < 0 && errno != EINTR) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(-pid, SIGKILL);
  Wait(pid);
  return -2;
}

RunResult Run(const std::vector<std::string>& args, const EnvExtras& env, const std::string& cwd) {
  RunResult r;
  r.command = Quote(Binary());
  for (const auto& a : args) r.command += " " + Quote(a);
  char out_name[] = "/tmp/pb_cli_out_XXXXXX";
  char err_name[] = "/tmp/pb_cli_err_XXXXXX";
  const int out_fd = ::mkstemp(out_name);
  const int err_fd = ::mkstemp(err_name);
  ExecData d = Prepare(args, env);
  const pid_t pid = ::fork();
  if (pid == 0) ExecChild(d, out_fd, err_fd, cwd, false);
  ::close(out_fd);
  ::close(err_fd);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) {
    r.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    r.signaled = true;
    r.exit_code = 128 + WTERMSIG(status);
  }
  r.out = ReadFile(out_name);
  r.err = ReadFile(err_name);
  ::unlink(out_name);
  ::unlink(err_name);
  return r;
}

pid_t Spawn(const std::vector<std::string>& args, const std::string& out_file,
            const std::string& err_file, const EnvExtras& env) {
  ExecData d = Prepare(args, env);
  const int out_fd = OpenOut(out_file);
  const int err_fd = OpenOut(err_file);
  const pid_t pid = ::fork();
  if (pid == 0) ExecChild(d, out_fd, err_fd, "", true);
  // Also from the parent, so the group exists before any kill(-pid).
  ::setpgid(pid, pid);
  ::close(out_fd);
  ::close(err_fd);
  return pid;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteFile(const std::string& path, const std::string& text) {
  const fs::path p(path);
  if (p.has_parent_path()) fs::create_directories(p.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path);
}

bool Exists(const std::string& path) {
  std::error_code ec;
  return fs::exists(path, ec);
}

Json ReadJson(const std::string& path) {
  const std::string text = ReadFile(path);
  Json j = Json::parse(text, nullptr, false);
  return j;
}

std::vector<Json> ReadJsonLines(const std::string& path) {
  std::vector<Json> out;
  std::istringstream in(ReadFile(path));
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) out.push_back(Json::parse(line, nullptr, false));
  return out;
}

std::vector<std::string> ListFiles(const std::string& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  if (!fs::exists(dir, ec)) return out;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec))
    if (it->is_regular_file()) out.push_back(fs::relative(it->path(), dir).string());
  std::sort(out.begin(), out.end());
  return out;
}

std::string WriteWorkflow(const std::string& path, const std::string& yaml) {
  std::string text = yaml;
  auto replace_all = [&](const std::string& from, const std::string& to) {
    for (size_t pos = 0; (pos = text.find(from, pos)) != std::string::npos; pos += to.size())
      text.replace(pos, from.size(), to);
  };
  replace_all("$PLUGIN", "\"" + std::string(TestPlugin()) + "\"");
  replace_all("$HELLO", "\"" + std::string(HelloPlugin()) + "\"");
  WriteFile(path, text);
  return path;
}

int CountEntries(const std::string& cache_dir) {
  int n = 0;
  for (const std::string& f : ListFiles(cache_dir + "/entries"))
    if (f.size() > 5 && f.substr(f.size() - 5) == ".json") ++n;
  return n;
}

Json StageRecord(const Json& run_json, const std::string& stage) {
  if (run_json.is_object() && run_json.contains("stages"))
    for (const Json& s : run_json["stages"])
      if (s.value("stage", "") == stage) return s;
  return Json::object();
}

std::string StageStatus(const Json& run_json, const std::string& stage) {
  const Json s = StageRecord(run_json, stage);
  return s.contains("status") ? s.value("status", "?") : "<no record>";
}

std::string Statuses(const Json& run_json) {
  std::string out;
  if (run_json.is_object() && run_json.contains("stages"))
    for (const Json& s : run_json["stages"])
      out += s.value("stage", "?") + "=" + s.value("status", "?") + " ";
  return out;
}

}  // namespace pbtest
