#include "bench/records.h"

#include <string_view>

namespace canopy {
namespace {

template <typename T>
bool readAs(const nlohmann::json& json, const std::string& where, std::string_view kind,
            Record& out) {
  if (kind != T::kKind) return false;
  T record;
  JsonFieldReader reader(json, where);
  reader.skip("kind");
  record.visit(reader);
  reader.finish();
  out = std::move(record);
  return true;
}

}  // namespace

nlohmann::json recordToJson(const Record& record) {
  return std::visit(
      [](const auto& r) {
        nlohmann::json json = writeFields(r);
        json["kind"] = std::decay_t<decltype(r)>::kKind;
        return json;
      },
      record);
}

Record recordFromJson(const nlohmann::json& json, const std::string& where) {
  if (!json.is_object()) throwInputError("{}: a record must be a JSON object", where);
  if (!json.contains("kind") || !json["kind"].is_string())
    throwInputError("{}: key 'kind' is missing or not a string", where);
  const std::string kind = json["kind"].get<std::string>();
  Record record;
  if (readAs<TreeRecord>(json, where, kind, record) ||
      readAs<BakeRecord>(json, where, kind, record) ||
      readAs<ViewRecord>(json, where, kind, record) ||
      readAs<ForestRecord>(json, where, kind, record) ||
      readAs<PoppingRecord>(json, where, kind, record) ||
      readAs<SkipRecord>(json, where, kind, record))
    return record;
  throwInputError("{}: unknown record kind '{}' (tree, bake, view, forest, popping, skip)", where,
                  kind);
}

const char* kindOf(const Record& record) {
  return std::visit([](const auto& r) { return std::decay_t<decltype(r)>::kKind; }, record);
}

const std::string& recordKeyOf(const Record& record) {
  return std::visit([](const auto& r) -> const std::string& { return r.recordKey; }, record);
}

std::string& recordKeyOf(Record& record) {
  return std::visit([](auto& r) -> std::string& { return r.recordKey; }, record);
}

}  // namespace canopy
