// The .graph / .cyb container (R1-IN-002, R1-IN-006): TOML front matter up to the first line
// starting with "~~~", then sections "~~~name" each with its bytes. The container keeps every
// byte it read, so serialize(parse(f)) == f for every file it accepts.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "r1/spec/status.hpp"

namespace r1 {

struct ContainerFile {  // one [[files]] entry of the front matter
  std::string name;
  std::string format;
  std::optional<std::uint64_t> size;  // present: binary section of exactly this many bytes
};

struct ContainerSection {
  std::string name;
  std::string header;     // the raw "~~~name\n" (or "~~~name\r\n") line
  std::string_view body;  // the section's bytes (views into the parsed buffer)
  std::string separator;  // after a binary section: "" or "\n" before the next header
  bool binary = false;
  std::uint64_t offset = 0;  // byte offset of the body in the file
};

struct Container {
  std::string_view front_matter;  // raw bytes before the first section
  std::vector<ContainerFile> files;
  std::vector<ContainerSection> sections;

  const ContainerSection* find(std::string_view name) const;
  std::string serialize() const;
};

// Parses `bytes` (which must outlive the container). `file` names the input in messages.
Result<Container> parse_container(std::string_view bytes, const std::string& file);

}  // namespace r1
