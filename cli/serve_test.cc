#include "cli/serve_command.h"

#include <arpa/inet.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "base/testing/temp_dir.h"

namespace pb {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

class ServeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = std::filesystem::path(temp_.path()) / "campaign";
    std::filesystem::create_directories(root_ / "report" / "viewer");
    std::filesystem::create_directories(root_ / "runs" / "room hpm");
    std::ofstream(root_ / "report" / "viewer" / "index.html") << "<!doctype html>viewer";
    std::ofstream(root_ / "runs" / "room hpm" / "model.glb", std::ios::binary) << std::string("glTF\2\0\0\0", 8);
    std::ofstream(std::filesystem::path(temp_.path()) / "secret.txt") << "outside";
    std::filesystem::create_symlink(std::filesystem::path(temp_.path()) / "secret.txt", root_ / "link.txt");
  }

  // One request over a real socket to ServeOneRequest.
  std::string Request(const std::string& request) {
    uint16_t port = 0;
    Expected<int> listener = ListenLoopback(0, &port);
    EXPECT_TRUE(listener.ok()) << listener.status().message();
    if (!listener.ok()) return "";
    std::thread server([&] {
      const int client = ::accept(*listener, nullptr, nullptr);
      ServeOneRequest(client, root_);
    });
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    address.sin_port = htons(port);
    EXPECT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
    ::send(fd, request.data(), request.size(), 0);
    std::string response;
    char buffer[4096];
    for (ssize_t n; (n = ::recv(fd, buffer, sizeof(buffer), 0)) > 0;) response.append(buffer, size_t(n));
    ::close(fd);
    server.join();
    ::close(*listener);
    return response;
  }

  testing::TempDir temp_;
  std::filesystem::path root_;
};

TEST_F(ServeTest, ResolvesFilesFoldersAndEscapesInsideTheRoot) {
  auto viewer = ResolveStaticPath(root_, "/report/viewer/?run=a");
  ASSERT_TRUE(viewer.ok()) << viewer.status().message();
  EXPECT_EQ(viewer->filename(), "index.html");
  auto model = ResolveStaticPath(root_, "/runs/room%20hpm/./model.glb#x");
  ASSERT_TRUE(model.ok()) << model.status().message();
  EXPECT_EQ(model->parent_path().filename(), "room hpm");
  EXPECT_EQ(ResolveStaticPath(root_, "/runs/../../secret.txt").status().code(), Status::Code::kInvalid);
  EXPECT_EQ(ResolveStaticPath(root_, "/%2e%2e/secret.txt").status().code(), Status::Code::kInvalid);
  EXPECT_EQ(ResolveStaticPath(root_, "/link.txt").status().code(), Status::Code::kInvalid);
  EXPECT_EQ(ResolveStaticPath(root_, "/bad%zz").status().code(), Status::Code::kInvalid);
  EXPECT_EQ(ResolveStaticPath(root_, "relative").status().code(), Status::Code::kInvalid);
  EXPECT_EQ(ResolveStaticPath(root_, "/missing.glb").status().code(), Status::Code::kNotFound);
  EXPECT_EQ(ResolveStaticPath(root_, "/runs/").status().code(), Status::Code::kNotFound);  // no listings
}

TEST_F(ServeTest, ContentTypesTheViewerNeeds) {
  EXPECT_EQ(ContentTypeFor("a/model.GLB"), "model/gltf-binary");
  EXPECT_EQ(ContentTypeFor("basis_transcoder.wasm"), "application/wasm");
  EXPECT_THAT(ContentTypeFor("three.module.js"), StartsWith("text/javascript"));
  EXPECT_THAT(ContentTypeFor("index.html"), StartsWith("text/html"));
  EXPECT_EQ(ContentTypeFor("models.json"), "application/json");
  EXPECT_EQ(ContentTypeFor("noext"), "application/octet-stream");
}

TEST_F(ServeTest, AnswersGetHeadAndErrorsOverHttp) {
  const std::string get = Request("GET /runs/room%20hpm/model.glb HTTP/1.1\r\nHost: x\r\n\r\n");
  EXPECT_THAT(get, StartsWith("HTTP/1.1 200 OK\r\n"));
  EXPECT_THAT(get, HasSubstr("Content-Type: model/gltf-binary\r\n"));
  EXPECT_THAT(get, HasSubstr("Content-Length: 8\r\n"));
  EXPECT_EQ(get.substr(get.size() - 8), std::string("glTF\2\0\0\0", 8));
  const std::string head = Request("HEAD /report/viewer/ HTTP/1.1\r\n\r\n");
  EXPECT_THAT(head, StartsWith("HTTP/1.1 200 OK\r\n"));
  EXPECT_THAT(head, HasSubstr("Content-Length: 21\r\n"));
  EXPECT_EQ(head.find("viewer", head.find("\r\n\r\n")), std::string::npos);  // no body
  EXPECT_THAT(Request("GET /nothing HTTP/1.1\r\n\r\n"), StartsWith("HTTP/1.1 404 "));
  EXPECT_THAT(Request("GET /../secret.txt HTTP/1.1\r\n\r\n"), StartsWith("HTTP/1.1 403 "));
  EXPECT_THAT(Request("POST / HTTP/1.1\r\n\r\n"), StartsWith("HTTP/1.1 405 "));
  EXPECT_THAT(Request("garbage\r\n\r\n"), StartsWith("HTTP/1.1 400 "));
}

}  // namespace
}  // namespace pb
