#pragma once
// Internal to sim/core: what the scene document's files share about toml++ nodes (their type
// names and file:line, keys in file order) and the --set overrides (SceneOverrides.cpp).
#include <toml++/toml.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

namespace ferro {
namespace scene_detail {

// TOML's own names for the types, which is what users see in their file.
inline const char* typeName(const toml::node& n)
{
    switch (n.type()) {
    case toml::node_type::string: return "string";
    case toml::node_type::integer: return "integer";
    case toml::node_type::floating_point: return "float";
    case toml::node_type::boolean: return "boolean";
    case toml::node_type::array: return "array";
    case toml::node_type::table: return "table";
    case toml::node_type::date: return "date";
    case toml::node_type::time: return "time";
    case toml::node_type::date_time: return "date-time";
    case toml::node_type::none: break;
    }
    return "nothing";
}

// "file:line" of a node. Nodes built in code rather than parsed have no source; they
// fall back to the document itself.
inline std::string locate(const toml::node& n, const std::string& docPath)
{
    const toml::source_region& src = n.source();
    std::string file = src.path && !src.path->empty() ? *src.path : docPath;
    if (src.begin.line == 0)
        return file;
    return file + ":" + std::to_string(src.begin.line);
}

// A table with no keys, standing in for an absent section or sub-table.
inline const toml::table& emptyTable()
{
    static const toml::table empty;
    return empty;
}

// Keys of `table` in file order (toml::table iterates alphabetically), so that the
// first offending key reported is the first one the user wrote; keys set by --set
// come after those of the file.
inline std::vector<std::pair<std::string, const toml::node*>> keysInFileOrder(const toml::table& table,
                                                                       const std::string& docPath)
{
    std::vector<std::pair<std::string, const toml::node*>> keys;
    for (const auto& [k, v] : table)
        keys.emplace_back(std::string(k.str()), &v);
    auto order = [&](const toml::node* n) {
        const toml::source_region& src = n->source();
        return std::make_pair(!src.path || *src.path != docPath, src.begin.line);
    };
    std::stable_sort(keys.begin(), keys.end(),
                     [&](const auto& a, const auto& b) { return order(a.second) < order(b.second); });
    return keys;
}

/// Applies one `--set section.key=value` to `root` (SceneOverrides.cpp); SceneError on a bad one.
void applyOverride(toml::table& root, const std::string& arg);

} // namespace scene_detail
} // namespace ferro
