#include "viosfm/util/option_fields.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

enum class Color { kRed, kBlue };
std::string OptionText(Color color) {
  return color == Color::kRed ? "red" : "blue";
}
void ParseOptionText(const std::string& text, Color* color) {
  if (text == "red") {
    *color = Color::kRed;
  } else if (text == "blue") {
    *color = Color::kBlue;
  } else {
    throw InputError("expected red or blue");
  }
}

struct InnerOptions {
  double ratio = 0.02 / 3.0;
  int num_threads = 2;
  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"ratio", "a ratio", kShapesStoredData}, self.ratio);
    visit({"num_threads", "worker threads", kRunOnly}, self.num_threads);
  }
};

struct OuterOptions {
  bool flag = true;
  int64_t stamp_ns = 5'000'000;
  uint64_t seed = 7;
  std::string name = "x";
  std::vector<int> spans = {10, 50};
  Color color = Color::kBlue;
  InnerOptions inner;
  InnerOptions later;
  bool use_later = false;
  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"flag", "a flag", kShapesStoredData}, self.flag);
    visit({"stamp_ns", "a time", kShapesStoredData}, self.stamp_ns);
    visit({"seed", "a seed", kShapesStoredData}, self.seed);
    visit({"name", "a name", kRunOnly}, self.name);
    visit({"spans", "spans", kShapesStoredData}, self.spans);
    visit({"color", "a color", kShapesStoredData}, self.color);
    VisitOptionGroup({"inner", "", kShapesStoredData}, self.inner, visit);
    VisitOptionGroup({"later", "", kShapesStoredData, self.use_later}, self.later, visit);
    visit({"use_later", "use later", kRunOnly}, self.use_later);
  }
};

using KeyValues = std::vector<std::pair<std::string, std::string>>;

TEST(OptionFields, KeyValuesInOrderWithTheirTexts) {
  const KeyValues expected = {{"flag", "true"},
                              {"stamp_ns", "5000000"},
                              {"seed", "7"},
                              {"name", "x"},
                              {"spans", "10,50"},
                              {"color", "blue"},
                              {"inner.ratio", "0.006666666667"},
                              {"inner.num_threads", "2"},
                              {"use_later", "false"}};
  EXPECT_EQ(OptionsToKeyValues(OuterOptions{}), expected);
  EXPECT_EQ(OptionsToKeyValues(InnerOptions{}, "p.")[1],
            KeyValues::value_type("p.num_threads", "2"));
}

TEST(OptionFields, GroupsPassOnActiveAndRunOnly) {
  OuterOptions options;
  options.use_later = true;
  const KeyValues keys = OptionsToKeyValues(options);
  ASSERT_EQ(keys.size(), 11u);
  EXPECT_EQ(keys[8].first, "later.ratio");
  const KeyValues stored = StoredDataOptions(options);
  const KeyValues expected = {{"flag", "true"},
                              {"stamp_ns", "5000000"},
                              {"seed", "7"},
                              {"spans", "10,50"},
                              {"color", "blue"},
                              {"inner.ratio", "0.006666666667"},
                              {"later.ratio", "0.006666666667"}};
  EXPECT_EQ(stored, expected);
}

TEST(OptionFields, DescriptionsListEveryFieldWithItsDefault) {
  const std::vector<OptionDescription> descriptions = OptionDescriptions<OuterOptions>();
  ASSERT_EQ(descriptions.size(), 11u);  // the inactive group too
  EXPECT_EQ(descriptions[0].key, "flag");
  EXPECT_EQ(descriptions[0].default_text, "true");
  EXPECT_EQ(descriptions[0].help, "a flag");
  EXPECT_EQ(descriptions[7].key, "inner.num_threads");
  EXPECT_EQ(descriptions[7].effect, kRunOnly);
  EXPECT_EQ(descriptions[8].key, "later.ratio");
}

TEST(OptionFields, SetFromTextRoundTrips) {
  OuterOptions options;
  SetOptionFromText(options, "flag", "false");
  SetOptionFromText(options, "stamp_ns", "-12");
  SetOptionFromText(options, "seed", "18446744073709551615");
  SetOptionFromText(options, "name", "a b");
  SetOptionFromText(options, "spans", "3,4,5");
  SetOptionFromText(options, "color", "red");
  SetOptionFromText(options, "inner.ratio", "1e-3");
  SetOptionFromText(options, "later.num_threads", "8");
  EXPECT_FALSE(options.flag);
  EXPECT_EQ(options.stamp_ns, -12);
  EXPECT_EQ(options.seed, 18446744073709551615u);
  EXPECT_EQ(options.name, "a b");
  EXPECT_EQ(options.spans, (std::vector<int>{3, 4, 5}));
  EXPECT_EQ(options.color, Color::kRed);
  EXPECT_DOUBLE_EQ(options.inner.ratio, 1e-3);
  EXPECT_EQ(options.later.num_threads, 8);
  // Every text written parses back to the same value.
  OuterOptions copy;
  for (const auto& [key, value] : OptionsToKeyValues(options)) SetOptionFromText(copy, key, value);
  EXPECT_EQ(OptionsToKeyValues(copy), OptionsToKeyValues(options));
}

TEST(OptionFields, BadTextNamesTheKeyAndTheText) {
  OuterOptions options;
  const auto message = [&](const std::string& key, const std::string& text) {
    try {
      SetOptionFromText(options, key, text);
    } catch (const InputError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("inner.num_threads", "2.5"),
            "option inner.num_threads: '2.5': expected an integer");
  EXPECT_EQ(message("flag", "yes"), "option flag: 'yes': expected true or false");
  EXPECT_EQ(message("seed", "-1"), "option seed: '-1': expected an integer >= 0");
  EXPECT_EQ(message("color", "green"), "option color: 'green': expected red or blue");
  EXPECT_EQ(message("inner.ratio", ""), "option inner.ratio: '': expected a number");
  EXPECT_EQ(message("spans", "1,x"), "option spans: '1,x': expected comma-separated integers");
  EXPECT_EQ(message("nope", "1"), "unknown option 'nope'");
  EXPECT_EQ(options.inner.num_threads, 2);
}

}  // namespace
}  // namespace viosfm
