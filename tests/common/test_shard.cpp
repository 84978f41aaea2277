// The command line a sharded tool records in its part (common/shard/shard.h): the options of the
// shard and the output left out with their values, in each form CLI11 takes them; the merge's
// reading of it back; and the argc and argv a tool's run(args) parses.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shard/shard.h"

namespace penumbra::shard {
namespace {

using Args = std::vector<std::string>;

TEST(ShardArgs, TheNamedOptionsAreLeftOutWithTheirValues) {
  const Args args = {"--quick", "--shard", "1/3", "--part", "p.json", "--frames", "2", "-o", "out", "--width", "64"};
  EXPECT_EQ(without_options(args, {"--shard", "--part", "--output", "-o"}), (Args{"--quick", "--frames", "2", "--width", "64"}));
  // Only the names given: the demo keeps its -o (the merge gives its own after the rest).
  EXPECT_EQ(without_options(args, {"--shard", "--part"}), (Args{"--quick", "--frames", "2", "-o", "out", "--width", "64"}));
}

TEST(ShardArgs, AValueJoinedToItsNameIsOneArgument) {
  const Args args = {"--shard=0/2", "--frames", "2", "--part=p.json", "-oout", "-o=out", "--output=out", "--json=c.json", "--seeds", "3"};
  EXPECT_EQ(without_options(args, {"--shard", "--part", "--output", "-o"}), (Args{"--frames", "2", "--json=c.json", "--seeds", "3"}));
  // -oVALUE belongs to a one-letter name only, and a longer name's prefix is not the name.
  EXPECT_EQ(without_options({"-oout", "--shards", "4", "--partition=x", "--json", "c.json"}, {"--shard", "--part", "--json"}),
            (Args{"-oout", "--shards", "4", "--partition=x"}));
  EXPECT_EQ(without_options({"-o", "out", "--other", "1"}, {"-o"}), (Args{"--other", "1"}));
}

TEST(ShardArgs, ANameAloneTakesTheNextArgumentWhateverItIs) {
  EXPECT_EQ(without_options({"--part", "--shard", "--frames", "2"}, {"--shard", "--part"}), (Args{"--frames", "2"}));
  EXPECT_EQ(without_options({"--frames", "2", "--part"}, {"--shard", "--part"}), (Args{"--frames", "2"}));
  EXPECT_EQ(without_options({}, {"--shard"}), Args{});
}

TEST(ShardArgs, TheMergeReadsTheStoredArgumentsOrRefusesNamingTheFile) {
  EXPECT_EQ(stored_args({{"args", {"--frames", "2"}}}, "p.json"), (Args{"--frames", "2"}));
  EXPECT_EQ(stored_args({{"args", nlohmann::json::array()}}, "p.json"), Args{});
  for (const nlohmann::json& settings : {nlohmann::json::object(), nlohmann::json{{"args", "--frames 2"}},
                                         nlohmann::json{{"args", {"--frames", 2}}}, nlohmann::json{{"args", nullptr}}}) {
    try {
      stored_args(settings, "parts/p.json");
      ADD_FAILURE() << settings.dump() << " read";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "parts/p.json: settings.args: not a list of arguments") << settings.dump();
    }
  }
}

TEST(ShardArgs, ArgvHoldsTheToolsNameAndTheArguments) {
  const Args args = {"--frames", "2", ""};
  Argv argv("penumbra-bench", args);
  ASSERT_EQ(argv.argc(), 4);
  EXPECT_STREQ(argv.argv()[0], "penumbra-bench");
  for (std::size_t i = 0; i < args.size(); ++i) EXPECT_EQ(argv.argv()[i + 1], args[i]);
  EXPECT_EQ(Argv("penumbra-demo", {}).argc(), 1);
}

}  // namespace
}  // namespace penumbra::shard
