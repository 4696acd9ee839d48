#include "formats/colmap_database.h"

#include <sqlite3.h>

#include <algorithm>
#include <cstring>

#include "base/errors.h"
#include "base/format.h"

namespace p2n {
namespace {

constexpr uint64_t kMaxNumImages = 2147483647;  // COLMAP's pair ids: id1 * kMaxNumImages + id2, id1 < id2

// A prepared statement, finalised when it goes out of scope.
class Statement {
 public:
  Statement(sqlite3* db, const std::filesystem::path& path, const char* sql) : path_(path) {
    if (sqlite3_prepare_v2(db, sql, -1, &statement_, nullptr) != SQLITE_OK) Fail(db, sql);
  }
  ~Statement() { sqlite3_finalize(statement_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  sqlite3_stmt* get() const { return statement_; }
  // SQLITE_ROW or SQLITE_DONE; anything else throws.
  int Step() {
    const int code = sqlite3_step(statement_);
    if (code != SQLITE_ROW && code != SQLITE_DONE) Fail(sqlite3_db_handle(statement_), sqlite3_sql(statement_));
    return code;
  }

 private:
  [[noreturn]] void Fail(sqlite3* db, const char* sql) const {
    throw ExternalToolError(format("COLMAP's database '{}': '{}' failed: {}", path_.string(), sql, sqlite3_errmsg(db)));
  }

  std::filesystem::path path_;
  sqlite3_stmt* statement_ = nullptr;
};

void Execute(sqlite3* db, const std::filesystem::path& path, const std::string& sql) {
  Statement statement(db, path, sql.c_str());
  statement.Step();
}

// The largest id of `column` in `table` (0 when empty).
int64_t MaxId(sqlite3* db, const std::filesystem::path& path, const std::string& table, const std::string& column) {
  Statement statement(db, path, format("SELECT IFNULL(MAX({}), 0) FROM {}", column, table).c_str());
  statement.Step();
  return sqlite3_column_int64(statement.get(), 0);
}

// Copies every row of `table` from the attached database `part` into the main one, `assignments` applied ("image_id
// = image_id + 7"): through a temporary table, whatever the columns of this COLMAP version's table.
void CopyRows(sqlite3* db, const std::filesystem::path& path, const std::string& table,
              const std::string& assignments) {
  Execute(db, path, format("CREATE TEMP TABLE copied AS SELECT * FROM part.{}", table));
  Execute(db, path, format("UPDATE copied SET {}", assignments));
  Execute(db, path, format("INSERT INTO main.{} SELECT * FROM copied", table));
  Execute(db, path, "DROP TABLE copied");
}

}  // namespace

uint64_t ColmapPairId(uint32_t image_id1, uint32_t image_id2) {
  if (image_id1 > image_id2) std::swap(image_id1, image_id2);
  return kMaxNumImages * image_id1 + image_id2;
}

ColmapDatabase::ColmapDatabase(const std::filesystem::path& path, bool read_only) : path_(path) {
  if (sqlite3_open_v2(path.c_str(), &db_, read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE, nullptr) !=
      SQLITE_OK) {
    const std::string why = db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    throw ExternalToolError(format("cannot open COLMAP's database '{}': {}", path.string(), why));
  }
}

ColmapDatabase::~ColmapDatabase() { sqlite3_close(db_); }

std::vector<ColmapDatabaseImage> ColmapDatabase::Images() const {
  Statement statement(db_, path_, "SELECT image_id, name FROM images");
  std::vector<ColmapDatabaseImage> images;
  while (statement.Step() == SQLITE_ROW) {
    const unsigned char* name = sqlite3_column_text(statement.get(), 1);
    images.push_back({static_cast<uint32_t>(sqlite3_column_int64(statement.get(), 0)),
                      name != nullptr ? reinterpret_cast<const char*>(name) : ""});
  }
  // As std::string orders them, which is COLMAP's order for sequential matching.
  std::sort(images.begin(), images.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  return images;
}

SiftDescriptors ColmapDatabase::Descriptors(uint32_t image_id) const {
  Statement statement(db_, path_, "SELECT rows, cols, data FROM descriptors WHERE image_id = ?");
  sqlite3_bind_int64(statement.get(), 1, image_id);
  if (statement.Step() != SQLITE_ROW) return SiftDescriptors(128, 0);
  const int64_t rows = sqlite3_column_int64(statement.get(), 0), cols = sqlite3_column_int64(statement.get(), 1);
  const void* data = sqlite3_column_blob(statement.get(), 2);
  const int64_t bytes = sqlite3_column_bytes(statement.get(), 2);
  if (rows < 0 || cols != 128 || bytes != rows * cols || (rows > 0 && data == nullptr)) {
    throw ExternalToolError(
        format("COLMAP's database '{}': image {}'s descriptors are {} x {} with {} bytes, not rows x 128 uint8 values; "
               "delete the sfm stage's folder and run it again",
               path_.string(), image_id, rows, cols, bytes));
  }
  SiftDescriptors descriptors(128, rows);
  if (rows > 0) std::memcpy(descriptors.data(), data, bytes);
  return descriptors;
}

std::map<uint32_t, size_t> ColmapDatabase::FeatureCounts() const {
  Statement statement(db_, path_, "SELECT image_id, rows FROM keypoints");
  std::map<uint32_t, size_t> counts;
  while (statement.Step() == SQLITE_ROW) {
    counts[static_cast<uint32_t>(sqlite3_column_int64(statement.get(), 0))] =
        static_cast<size_t>(std::max<sqlite3_int64>(sqlite3_column_int64(statement.get(), 1), 0));
  }
  return counts;
}

std::vector<VerifiedPair> ColmapDatabase::VerifiedPairs() const {
  Statement statement(db_, path_, "SELECT pair_id, rows FROM two_view_geometries WHERE rows > 0");
  std::vector<VerifiedPair> pairs;
  while (statement.Step() == SQLITE_ROW) {
    const auto pair_id = static_cast<uint64_t>(sqlite3_column_int64(statement.get(), 0));
    pairs.push_back({static_cast<uint32_t>(pair_id / kMaxNumImages), static_cast<uint32_t>(pair_id % kMaxNumImages),
                     static_cast<size_t>(sqlite3_column_int64(statement.get(), 1))});
  }
  return pairs;
}

bool ColmapDatabase::HasMatches(uint32_t image_id1, uint32_t image_id2) const {
  Statement statement(db_, path_, "SELECT 1 FROM matches WHERE pair_id = ?");
  sqlite3_bind_int64(statement.get(), 1, static_cast<sqlite3_int64>(ColmapPairId(image_id1, image_id2)));
  return statement.Step() == SQLITE_ROW;
}

void ColmapDatabase::CreateBlock(const std::filesystem::path& database, const std::filesystem::path& path,
                                 const std::vector<uint32_t>& image_ids) {
  sqlite3* created = nullptr;
  const bool made =
      sqlite3_open_v2(path.c_str(), &created, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) == SQLITE_OK;
  const std::string why = made ? "" : created != nullptr ? sqlite3_errmsg(created) : "out of memory";
  sqlite3_close(created);
  if (!made) throw ExternalToolError(format("cannot create the database '{}': {}", path.string(), why));
  ColmapDatabase block(path);
  block.Attach(database);
  Execute(block.db_, path, "BEGIN TRANSACTION");
  std::vector<std::string> schema;
  {
    Statement tables(block.db_, path,
                     "SELECT sql FROM part.sqlite_master WHERE type IN ('table', 'index') AND sql IS NOT NULL AND "
                     "name NOT LIKE 'sqlite_%' ORDER BY type DESC");  // tables before their indexes
    while (tables.Step() == SQLITE_ROW) {
      schema.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(tables.get(), 0)));
    }
  }
  for (const std::string& sql : schema) Execute(block.db_, path, sql);
  std::string ids;
  for (const uint32_t id : image_ids) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
  Execute(block.db_, path, "INSERT INTO main.cameras SELECT * FROM part.cameras");
  Execute(block.db_, path, "INSERT INTO main.images SELECT * FROM part.images");
  Execute(block.db_, path, "UPDATE main.images SET name = image_id");  // COLMAP's lists of pairs split names at spaces
  Execute(block.db_, path,
          format("INSERT INTO main.keypoints SELECT * FROM part.keypoints WHERE image_id IN ({})", ids));
  Execute(block.db_, path, "COMMIT");
  Execute(block.db_, path, "DETACH DATABASE part");
}

void ColmapDatabase::AppendMatches(const std::filesystem::path& other) {
  Attach(other);
  Execute(db_, path_, "BEGIN TRANSACTION");
  Execute(db_, path_, "INSERT INTO main.matches SELECT * FROM part.matches");
  Execute(db_, path_, "INSERT INTO main.two_view_geometries SELECT * FROM part.two_view_geometries");
  Execute(db_, path_, "COMMIT");
  Execute(db_, path_, "DETACH DATABASE part");
}

void ColmapDatabase::Attach(const std::filesystem::path& other) {
  Statement attach(db_, path_, "ATTACH DATABASE ? AS part");
  sqlite3_bind_text(attach.get(), 1, other.c_str(), -1, SQLITE_TRANSIENT);
  attach.Step();
}

uint32_t ColmapDatabase::AppendImages(const std::filesystem::path& other, std::optional<uint32_t> camera) {
  const int64_t images = MaxId(db_, path_, "images", "image_id"), cameras = MaxId(db_, path_, "cameras", "camera_id");
  Attach(other);
  Execute(db_, path_, "BEGIN TRANSACTION");
  if (!camera) CopyRows(db_, path_, "cameras", format("camera_id = camera_id + {}", cameras));
  CopyRows(db_, path_, "images",
           format("image_id = image_id + {}, camera_id = {}", images,
                  camera ? std::to_string(*camera) : format("camera_id + {}", cameras)));
  for (const char* table : {"keypoints", "descriptors"}) {
    CopyRows(db_, path_, table, format("image_id = image_id + {}", images));
  }
  Execute(db_, path_, "COMMIT");
  Execute(db_, path_, "DETACH DATABASE part");
  return camera ? *camera : static_cast<uint32_t>(cameras + 1);
}

void ColmapDatabase::WriteMatches(const std::vector<std::pair<std::pair<uint32_t, uint32_t>, FeatureMatches>>& pairs) {
  Execute(db_, path_, "BEGIN TRANSACTION");
  {
    Statement insert(db_, path_, "INSERT INTO matches(pair_id, rows, cols, data) VALUES(?, ?, 2, ?)");
    std::vector<uint32_t> data;
    for (const auto& [ids, matches] : pairs) {
      const bool swap = ids.first > ids.second;
      data.clear();
      for (const auto& [a, b] : matches) data.insert(data.end(), {swap ? b : a, swap ? a : b});
      sqlite3_reset(insert.get());
      sqlite3_bind_int64(insert.get(), 1, static_cast<sqlite3_int64>(ColmapPairId(ids.first, ids.second)));
      sqlite3_bind_int64(insert.get(), 2, static_cast<sqlite3_int64>(matches.size()));
      if (data.empty()) {
        sqlite3_bind_zeroblob(insert.get(), 3, 0);  // a pair without matches has a row too, as COLMAP writes it
      } else {
        sqlite3_bind_blob(insert.get(), 3, data.data(), static_cast<int>(data.size() * sizeof(uint32_t)),
                          SQLITE_TRANSIENT);
      }
      insert.Step();
    }
  }
  Execute(db_, path_, "COMMIT");
}

}  // namespace p2n
