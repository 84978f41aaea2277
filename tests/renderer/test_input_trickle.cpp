// gl::InputTrickle: keyboard input that arrives in one poll reaches ImGui 1.86 over several frames,
// in order, so that no press is lost (a press and release in one frame; BackSpace and Enter in one
// frame, where the text field handles only the first) and text and keys keep their order.
#include "gl/input_trickle.h"

#include <gtest/gtest.h>

#include <string>

namespace {

using penumbra::gl::InputTrickle;
constexpr int kShift = 340, kEnter = 257, kBackSpace = 259, kP = 80, k1 = 49;

// A frame's events as text: "+257" press, "-257" release, "'P'" a character.
std::string frame(InputTrickle& t) {
  std::string s;
  for (const auto& e : t.frame_starting()) {
    if (!s.empty()) s += ' ';
    s += e.is_char ? "'" + std::string(1, static_cast<char>(e.ch)) + "'" : (e.pressed ? "+" : "-") + std::to_string(e.key);
  }
  return s;
}

void tap(InputTrickle& t, int key) {
  t.key(key, true);
  t.key(key, false);
}

TEST(InputTrickle, APressAndItsReleaseInOnePollAreSeenInTwoFrames) {
  InputTrickle t;
  tap(t, kEnter);
  EXPECT_EQ(frame(t), "+257");
  EXPECT_EQ(frame(t), "-257");
  EXPECT_EQ(frame(t), "");
  EXPECT_TRUE(t.empty());
}

TEST(InputTrickle, EachNonModifierPressHasItsOwnFrame) {
  InputTrickle t;
  tap(t, kBackSpace);
  tap(t, kBackSpace);
  tap(t, kEnter);
  EXPECT_EQ(frame(t), "+259");
  EXPECT_EQ(frame(t), "-259");
  EXPECT_EQ(frame(t), "+259");
  EXPECT_EQ(frame(t), "-259 +257") << "a release and the next key's press share a frame";
  EXPECT_EQ(frame(t), "-257");
  EXPECT_TRUE(t.empty());
}

TEST(InputTrickle, TextAndKeysKeepTheirOrder) {
  // xdotool's "type P1" then "key BackSpace": shift+P, its character, 1, its character, BackSpace.
  InputTrickle t;
  t.key(kShift, true);
  t.key(kP, true);
  t.character('P');
  t.key(kP, false);
  t.key(kShift, false);
  t.key(k1, true);
  t.character('1');
  t.key(k1, false);
  tap(t, kBackSpace);
  EXPECT_EQ(frame(t), "+340 +80") << "the modifier rides with its key";
  EXPECT_EQ(frame(t), "'P'");
  EXPECT_EQ(frame(t), "-80 -340 +49");
  EXPECT_EQ(frame(t), "'1'");
  EXPECT_EQ(frame(t), "-49 +259") << "the BackSpace comes after the text it deletes";
  EXPECT_EQ(frame(t), "-259");
  EXPECT_TRUE(t.empty());
}

TEST(InputTrickle, TextWithoutKeysIsTakenInOneFrame) {
  InputTrickle t;
  for (char c : std::string("abc")) t.character(static_cast<unsigned char>(c));
  t.key(kShift, true);  // keys wait until the text is taken
  EXPECT_EQ(frame(t), "'a' 'b' 'c'");
  EXPECT_EQ(frame(t), "+340");
}

TEST(InputTrickle, ABacklogBeyondTheLimitIsTakenAtOnce) {
  InputTrickle t;
  for (std::size_t i = 0; i < InputTrickle::kMaxQueued; ++i) tap(t, kEnter);
  EXPECT_EQ(t.frame_starting().size(), 2 * InputTrickle::kMaxQueued) << "a window not drawn for long";
  EXPECT_TRUE(t.empty());
  tap(t, kEnter);
  EXPECT_EQ(frame(t), "+257");
}

}  // namespace
