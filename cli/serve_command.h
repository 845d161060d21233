// `pointbake serve [DIR] [--port N]`: serves a folder (a campaign's --out,
// e.g. out/demo) over HTTP on 127.0.0.1 only, so that a browser can open the
// 3-D viewer the report links (report/viewer/index.html) and load the models
// (browsers do not let a page loaded from file: fetch files). Static files
// only: GET and HEAD, no directory listings, nothing outside DIR (".."
// segments and symlinks leading out are refused). Prints the URL, then serves
// until interrupted (Ctrl-C).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "base/status.h"
#include "cli/cli.h"

namespace pb {

// Exit 0 when stopped by a signal after serving, 2 on bad usage or when the
// folder or the port cannot be used.
CliCommand ServeCommand();

// The file under `root` that the request target `target` ("/a/b.glb?x=1")
// names: percent-decoded, query dropped, "/" and folders to their
// index.html. Status::NotFound for a missing file, Status::Invalid for a
// target that is malformed or leaves `root` (also through symlinks).
Expected<std::filesystem::path> ResolveStaticPath(const std::filesystem::path& root,
                                                  const std::string& target);

// The Content-Type of a file by its extension (lower-case, e.g. ".glb" ->
// "model/gltf-binary", ".wasm" -> "application/wasm"); unknown ones are
// "application/octet-stream".
std::string ContentTypeFor(const std::filesystem::path& file);

// A listening socket on 127.0.0.1:`port` (0: any free port); the bound port
// into *bound_port.
Expected<int> ListenLoopback(uint16_t port, uint16_t* bound_port);

// Answers one HTTP request read from `client` with files under `root`, then
// closes `client`. (Blocking; `pointbake serve` runs one thread a connection.)
void ServeOneRequest(int client, const std::filesystem::path& root);

}  // namespace pb
