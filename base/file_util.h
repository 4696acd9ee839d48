#pragma once
// File helpers with the guarantees the cache rule needs: writes are atomic (temporary file, fsync, rename).

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace p2n {

// Writes `contents` to `path` atomically (a temporary file beside it, flushed to disk, renamed into place); UserError
// naming the file, the reason and what to check when it cannot (a full disk, a file-size limit, no permission).
void WriteFileAtomic(const std::filesystem::path& path, std::string_view contents);
void WriteBinaryFileAtomic(const std::filesystem::path& path, const std::vector<char>& bytes);
// Pretty JSON, classic locale, doubles that round-trip; atomic.
void WriteJsonAtomic(const std::filesystem::path& path, const nlohmann::json& value);
// The whole file as text; an empty string when it cannot be read (for logs and small files).
std::string ReadTextFile(const std::filesystem::path& path);
// Reads a JSON file; UserError naming the file when it is missing or malformed.
nlohmann::json ReadJsonFile(const std::filesystem::path& path);
// fsync on a folder, so that a rename inside it is durable.
void SyncDirectory(const std::filesystem::path& path);
// Lower-case extension without the dot ("JPG" -> "jpg").
std::string LowerExtension(const std::filesystem::path& path);
// Whether `path` lies inside the folder `root`, compared lexically (".." resolved, links not followed).
bool IsInside(const std::filesystem::path& root, const std::filesystem::path& path);

}  // namespace p2n
