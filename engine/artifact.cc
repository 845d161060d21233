#include "engine/artifact.h"

namespace pb {

Digest Artifact::ComputeDigest() const {
  Hasher h;
  h.Add("artifact-v1").Add(type);
  for (const auto& [name, file] : files) h.Add(name).Add(file.digest.Hex());
  h.Add(meta.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
  return h.Finish();
}

uint64_t Artifact::TotalBytes() const {
  uint64_t total = 0;
  for (const auto& [name, file] : files) total += file.size_bytes;
  return total;
}

nlohmann::json Artifact::ToJson() const {
  nlohmann::json files_json = nlohmann::json::object();
  for (const auto& [name, file] : files)
    files_json[name] = {{"digest", file.digest.Hex()}, {"size", file.size_bytes}};
  return {{"type", type}, {"files", files_json}, {"meta", meta}, {"digest", ComputeDigest().Hex()}};
}

Expected<Artifact> Artifact::FromJson(const nlohmann::json& j) {
  try {
    Artifact a;
    a.type = j.at("type").get<std::string>();
    for (const auto& [name, file] : j.at("files").items()) {
      PB_ASSIGN_OR_RETURN(Digest d, Digest::FromHex(file.at("digest").get<std::string>()));
      a.files[name] = StoredFile{d, file.at("size").get<uint64_t>()};
    }
    a.meta = j.value("meta", nlohmann::json::object());
    if (j.contains("digest") && j["digest"].get<std::string>() != a.ComputeDigest().Hex())
      return Status::Corrupt("artifact digest does not match its contents");
    return a;
  } catch (const nlohmann::json::exception& e) {
    return Status::Corrupt(std::string("malformed artifact record: ") + e.what());
  }
}

}  // namespace pb
