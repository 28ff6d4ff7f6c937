#pragma once
// Scene files: one TOML file describes a shot; each stage reads its own section.
//
// SceneDocument loads the file, applies command-line overrides (`--set a.b=value`) and
// hands out TableReader views. A TableReader reads typed keys with defaults and range
// checks, remembers which keys it consumed, and `finish()` rejects any key nobody read.
// Every error is a SceneError whose message is one line naming file, line and key:
//     examples/dish.toml:12: fluid.rest_density: must be > 0 (got -1200)
#include "sim/core/Types.hpp"

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace toml { inline namespace v3 { class table; class node; } }

namespace ferro {

/// Bad scene input. what() is a complete one-line message; tools exit with code 2.
class SceneError : public std::runtime_error {
public:
    /// Control characters in `what` (from a quoted key, or toml++'s "saw '\n'") are escaped
    /// (\n, \r, \xNN), so that what() is one line whatever the file holds.
    explicit SceneError(const std::string& what);
};

class SceneDocument;

/// Typed, checked access to one TOML table (a section such as [fluid]).
class TableReader {
public:
    TableReader(const SceneDocument& doc, const toml::table& table, std::string path);
    ~TableReader();
    TableReader(TableReader&&) noexcept;

    bool has(const std::string& key) const;
    double number(const std::string& key, double def) const;          ///< int or float
    double number(const std::string& key) const;                      ///< required
    double positive(const std::string& key, double def) const;        ///< > 0
    double positive(const std::string& key) const;                    ///< required, > 0
    double nonNegative(const std::string& key, double def) const;     ///< >= 0
    long integer(const std::string& key, long def) const;
    /// An integer in [lo, hi].
    int integerInRange(const std::string& key, int def, long lo, long hi) const;
    /// A number in [lo, hi].
    double numberInRange(const std::string& key, double def, double lo, double hi) const;
    bool boolean(const std::string& key, bool def) const;
    std::string string(const std::string& key, const std::string& def) const;
    std::string string(const std::string& key) const;                 ///< required
    /// A string that must be one of `choices`.
    std::string choice(const std::string& key, const std::vector<std::string>& choices,
                       const std::string& def) const;
    Vec3d vec3(const std::string& key, const Vec3d& def) const;        ///< [x, y, z]
    Vec3d vec3(const std::string& key) const;                         ///< required
    /// A non-zero vector, normalized.
    Vec3d unitVector(const std::string& key, const Vec3d& def) const;
    /// An axis-aligned box from two required corners; blames `maxKey` if it is empty.
    void box(const std::string& minKey, const std::string& maxKey, Vec3d& lo, Vec3d& hi) const;
    /// A path relative to the scene file's directory, resolved.
    std::string path(const std::string& key) const;
    /// A sub-table (absent = empty table) and an array of tables (absent = none).
    TableReader table(const std::string& key) const;
    std::vector<TableReader> tables(const std::string& key) const;
    /// An array of keyframe tables (e.g. [[magnets.keys]]), like tables(), after checking that
    /// each has a `time` >= 0 [s] and that the times never decrease; `label` names them in
    /// the errors ("every [[label]] needs a time"). The caller reads the rest (time included)
    /// and finish()es each.
    std::vector<TableReader> keyframes(const std::string& key, const std::string& label) const;
    /// Raw node access for stages with richer value types (nullptr if absent).
    const toml::node* node(const std::string& key) const;

    /// Throws if the table holds a key no getter consumed.
    void finish() const;
    /// The table's keys no getter has consumed so far, in file order (for a later parser of
    /// the rest of the table: SceneDocument::subset).
    std::vector<std::string> unread() const;
    /// Counts `key` as consumed: finish() passes it over.
    void ignore(const std::string& key) const;
    /// "file:line" of the table, or of one key if it is present.
    std::string where(const std::string& key = {}) const;
    [[noreturn]] void fail(const std::string& key, const std::string& message) const;
    const std::string& tablePath() const { return path_; }

private:
    /// Notes the key's type, range and default in the document's key table (noteSpec).
    void spec(const std::string& key, const std::string& type, const std::string& def) const;
    const SceneDocument* doc_;
    const toml::table* table_;
    std::string path_;
    struct Used;
    std::unique_ptr<Used> used_;
};

/// A parsed scene file with overrides applied.
class SceneDocument {
public:
    /// Parses `path` and applies `overrides` ("section.key=value"; value is TOML, or a bare
    /// string). Throws SceneError on a missing file, a syntax error or a bad override.
    static SceneDocument load(const std::string& path, const std::vector<std::string>& overrides = {});
    /// Same from a string (tests); `name` stands in for the file name in messages.
    static SceneDocument parse(const std::string& text, const std::string& name,
                               const std::vector<std::string>& overrides = {});
    SceneDocument(SceneDocument&&) noexcept;
    ~SceneDocument();

    TableReader section(const std::string& name) const;   ///< absent section = empty table
    bool hasSection(const std::string& name) const;
    const std::string& path() const { return path_; }
    std::string directory() const;
    /// This document seen through section `name` restricted to `keys`: its reader of that
    /// section counts every other key as consumed, so its finish() rejects only what its own
    /// parser leaves unread; messages name the scene's lines as here. For a parser that reads
    /// part of a section later and apart from the rest (a pressure solver's own [sim] keys).
    /// While this document records its reads, so does the subset, into the same log.
    std::shared_ptr<const SceneDocument> subset(const std::string& name, const std::vector<std::string>& keys) const;
    /// Rejects top-level keys that are not a known section of any stage.
    void checkSections(const std::vector<std::string>& known) const;
    /// Stable hash of the document (after overrides), to detect a changed scene on resume.
    std::string fingerprint() const;
    /// Stable hash of the named top-level sections only (absent ones count as empty), for
    /// caches that depend on part of the scene (ferro-sim's pre-roll).
    std::string fingerprint(const std::vector<std::string>& sections) const;
    const toml::table& root() const;

    /// From now on, note every key a TableReader of this document looks up (present or
    /// absent: a default is an input too). A stage parses its scene with this on to learn
    /// exactly which keys it reads: its parser is the one list of its inputs.
    void recordReads();
    /// The keys read since recordReads(), one line each in sorted order,
    /// `path.key = <TOML value>` or `path.key = (absent)`: the text of a stage's make stamp
    /// (scripts/shot.mk), which changes exactly when a value the stage read changes.
    std::string readsText() const;
    /// Stable hash of the keys read since recordReads() that the document sets, `ignore`d
    /// keys left out. Absent keys are left out too: their values are the code's defaults, and
    /// a key a newer version learns to read must not change the hash of an unchanged scene.
    /// It changes exactly when a value the stage read from the scene changes, so an edit to a
    /// section the stage never reads (a camera, the spikes) leaves it as it was.
    std::string readsFingerprint(const std::vector<std::string>& ignore = {}) const;
    /// The same keys with what the getter that read each one checks, one line each,
    /// `path.key<TAB>type and range<TAB>default` ("required" when there is none, "-" for keys
    /// read as raw nodes): the code's own key table, from which docs/reference/scene.md is
    /// generated (scripts/docs/scene-reference.py).
    std::string keySpecsText() const;
    /// Called by TableReader for each key it looks up (no-op unless recording).
    void noteRead(const std::string& tablePath, const std::string& key, const toml::node* node) const;
    /// Called by TableReader's typed getters: the key's type and range and its default. The
    /// outermost getter notes last (positive() after the number() it calls), so it wins.
    void noteSpec(const std::string& tablePath, const std::string& key, const std::string& type,
                  const std::string& def) const;

private:
    SceneDocument();
    std::string path_;
    std::shared_ptr<toml::table> root_;   // shared with the subsets
    /// A subset's section and the keys it shows (the rest its reader treats as consumed).
    std::string subsetSection_;
    std::vector<std::string> subsetKeys_;
    struct ReadLog;
    std::shared_ptr<ReadLog> reads_;   // shared with the subsets made while recording
};

/// 16 hex digits of a stable 64-bit hash (FNV-1a) of `text`.
std::string hashHex(const std::string& text);

/// Shortest round-trip text of a number, so a message shows exactly the value the user
/// wrote (-1200, 1e-07) rather than a fixed precision; and of a vector, as [x, y, z].
std::string formatNumber(double v);
std::string formatVec(const Vec3d& v);

} // namespace ferro
