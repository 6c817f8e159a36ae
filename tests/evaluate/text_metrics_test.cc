#include "stages/evaluate/text_metrics.h"

#include <gtest/gtest.h>

#include <cmath>

namespace docunfold::evaluate {
namespace {

TEST(EditDistance, ClassicCases) {
  EXPECT_EQ(EditDistance(U"kitten", U"sitting"), 3u);
  EXPECT_EQ(EditDistance(U"", U"abc"), 3u);
  EXPECT_EQ(EditDistance(U"abc", U""), 3u);
  EXPECT_EQ(EditDistance(U"same", U"same"), 0u);
  EXPECT_EQ(EditDistance(U"flaw", U"lawn"), 2u);
}

TEST(Utf8ToCodePoints, CountsCodePointsNotBytes) {
  EXPECT_EQ(Utf8ToCodePoints("na\xC3\xAFve").size(), 5u);  // naïve
  EXPECT_EQ(Utf8ToCodePoints("\xE2\x82\xAC"
                             "5")
                .size(),
            2u);                                               // €5
  EXPECT_EQ(Utf8ToCodePoints("\xF0\x9F\x93\x84").size(), 1u);  // U+1F4C4
  EXPECT_EQ(EditDistance(Utf8ToCodePoints("na\xC3\xAFve"), Utf8ToCodePoints("naive")), 1u);
  // A stray continuation byte or a cut-off sequence is one replacement char.
  EXPECT_EQ(Utf8ToCodePoints("a\x80"
                             "b"),
            std::u32string(U"a\uFFFDb"));
  EXPECT_EQ(Utf8ToCodePoints("a\xE2\x82"), std::u32string(U"a\uFFFD\uFFFD"));
  EXPECT_EQ(CodePointsToUtf8(Utf8ToCodePoints("na\xC3\xAFve \xE2\x82\xAC")),
            "na\xC3\xAFve \xE2\x82\xAC");
}

TEST(SplitWords, AnyWhitespaceSeparates) {
  const auto words = SplitWords(U"  one\ttwo\n\nthree\f ");
  ASSERT_EQ(words.size(), 3u);
  EXPECT_EQ(words[2], U"three");
  EXPECT_EQ(CollapseWhitespace(U"\n a  b\n\nc "), U"a b c");
}

TEST(WordsFound, AWordIsFoundAsASearchFindsIt) {
  // Punctuation at a word's ends and case do not matter; inside it they do.
  EXPECT_DOUBLE_EQ(WordsFound("Hello, \"World\".", "\xE2\x80\x9Chello\xE2\x80\x9D WORLD"), 1);
  EXPECT_DOUBLE_EQ(WordsFound("Pasta 14.66 Tea 2.90", "Pasta 14,66\nTea 2.90"), 0.75);
  EXPECT_DOUBLE_EQ(WordsFound("11/11/2026 Fee", "11/11/202 Fee"), 0.5);
  // Repeats count: two "Tea"s found once.
  EXPECT_DOUBLE_EQ(WordsFound("Tea Tea -- ...", "Tea"), 0.5);
  EXPECT_DOUBLE_EQ(WordsFound("na\xC3\xAFve", "NA\xC3\xAFVE"), 1);
  EXPECT_DOUBLE_EQ(WordsFound("", "anything"), 1);
}

TEST(CompareTexts, CerAndWerAreRelativeToTheReference) {
  const TextScores s = CompareTexts("the quick brown fox", "the quack brown fix jumps");
  EXPECT_EQ(s.reference_chars, 19u);
  EXPECT_EQ(s.ed, 2u + 6u);  // two substitutions, " jumps" inserted
  EXPECT_NEAR(s.cer, 8.0 / 19.0, 1e-12);
  EXPECT_EQ(s.reference_words, 4u);
  EXPECT_EQ(s.word_ed, 3u);  // quack, fix, +jumps
  EXPECT_NEAR(s.wer, 0.75, 1e-12);
}

TEST(CompareTexts, EmptyReferenceHasNoRate) {
  const TextScores s = CompareTexts("", "something");
  EXPECT_EQ(s.ed, 9u);
  EXPECT_TRUE(std::isnan(s.cer));
  EXPECT_TRUE(std::isnan(s.wer));
  const TextScores same = CompareTexts("identical text", "identical text");
  EXPECT_EQ(same.cer, 0.0);
  EXPECT_EQ(same.wer, 0.0);
}

}  // namespace
}  // namespace docunfold::evaluate
