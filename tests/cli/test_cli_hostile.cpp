// End to end: what a hostile or careless user gives the command line. Every numeric option of every
// command refuses NaN and infinities with one line; links planted in an output folder are never
// written through; the encoding of an input can be forced; error maps and reports of real maps
// hold no NaN or infinity.
#include <burnish/core/io/image.h>
#include <burnish/core/util/files.h>

#include "claiming_png.h"
#include "cli_run.h"
#include "temp_dir.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/stat.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using burnish::test::CliResult;
using burnish::test::lineCount;
using burnish::test::shellQuote;
using burnish::test::TempDir;
using burnish::test::writeClaimingPng;

// `burnish render` loads Mesa's drivers, whose allocations LeakSanitizer cannot attribute (see
// BURNISH_GL_TEST_ENV in tests/CMakeLists.txt); the setting reaches only this file's children.
CliResult runBurnish(const std::string& args, const std::string& environment = "") {
    ::setenv("ASAN_OPTIONS", "detect_leaks=0", 1);
    return burnish::test::runBurnish(args, environment);
}

// The subcommand names in a --help text's "Subcommands:" section.
std::vector<std::string> subcommandsOf(const std::string& help) {
    std::vector<std::string> names;
    std::istringstream in(help);
    std::string line;
    bool inside = false;
    while (std::getline(in, line)) {
        if (line.rfind("Subcommands:", 0) == 0) {
            inside = true;
            continue;
        }
        if (inside) {
            std::smatch m;
            if (std::regex_match(line, m, std::regex(R"(\s+([a-z][a-z0-9-]*)\b.*)")))
                names.push_back(m[1]);
            else if (!line.empty() && line[0] != ' ')
                inside = false;
        }
    }
    return names;
}

struct HelpOption {
    std::string name;
    std::string type;
};

// The options of a --help text that take a value, with the type name CLI11 shows.
std::vector<HelpOption> valueOptionsOf(const std::string& help) {
    std::vector<HelpOption> options;
    std::istringstream in(help);
    std::string line;
    const std::regex option(R"(\s+(?:-\w,)?(--[A-Za-z0-9-]+)(?:,-\w)?\s([A-Z][^\s]*).*)");
    while (std::getline(in, line)) {
        std::smatch m;
        if (std::regex_match(line, m, option)) options.push_back({m[1], m[2]});
    }
    return options;
}

// Every command path ("bake", "report approximations", ...) with its --help text.
void collectCommands(const std::string& path, std::vector<std::pair<std::string, std::string>>& out) {
    const CliResult help = runBurnish(path + " --help");
    ASSERT_EQ(help.exitCode, 0) << path << ": " << help.err;
    if (!path.empty()) out.emplace_back(path, help.out);
    for (const auto& sub : subcommandsOf(help.out))
        collectCommands(path.empty() ? sub : path + " " + sub, out);
}

// Every option that takes numbers, on every command, refuses "nan" before the command runs: exit
// non-zero, one line on stderr naming the option. The options come from each command's own
// --help, so a new option is covered as soon as it exists. Options of files and folders (types
// TEXT, FILE, DIR, PATH, NORMAL_MAP, IN, MESH) are left out: a file may be called "nan".
TEST(CliHostile, EveryNumericOptionRefusesNanAndInfinity) {
    std::vector<std::pair<std::string, std::string>> commands;
    collectCommands("", commands);
    ASSERT_GE(commands.size(), 7u);
    const std::set<std::string> pathTypes{"TEXT", "FILE", "DIR", "PATH", "NORMAL_MAP", "IN", "MESH"};
    int checked = 0;
    for (const auto& [command, help] : commands)
        for (const auto& option : valueOptionsOf(help)) {
            const std::string type = option.type.substr(0, option.type.find_first_of(":="));
            if (pathTypes.count(type)) continue;
            SCOPED_TRACE(command + " " + option.name + " nan");
            const CliResult r = runBurnish(command + " " + option.name + " nan");
            EXPECT_NE(r.exitCode, 0);
            EXPECT_EQ(lineCount(r.err), 1) << r.err;
            EXPECT_EQ(r.err.rfind("burnish: error: ", 0), 0u) << r.err;
            EXPECT_NE(r.err.find(option.name), std::string::npos) << r.err;
            ++checked;
        }
    // render alone has more than twenty numeric options; a broken help parser finds none.
    EXPECT_GT(checked, 40);
    // Infinities, inside lists and values too large for a double, too. (Options with a range may
    // answer with their range first: still one line naming the option.)
    for (const auto& [args, option] : std::vector<std::pair<std::string, std::string>>{
             {"render --light-dir 0,nan,1", "--light-dir"},
             {"render --specular 0.04,inf,0.04", "--specular"},
             {"evaluate x.png --power 64 1e999", "--power"},
             {"evaluate x.png --half-angles 0,5,-inf", "--half-angles"},
             {"render --yaw Infinity", "--yaw"},
             {"render --pitch -inf", "--pitch"},
             {"render --exposure NaN", "--exposure"},
             {"render --distance 1e400", "--distance"},
             {"bake x.png --power inf", "--power"},
             {"env --out x --top-power -nan", "--top-power"}}) {
        const CliResult r = runBurnish(args);
        EXPECT_NE(r.exitCode, 0) << args;
        EXPECT_EQ(lineCount(r.err), 1) << args << ": " << r.err;
        EXPECT_NE(r.err.find(option + ":"), std::string::npos) << args << ": " << r.err;
    }
}

// Links planted in a shared output folder at every name the old temporary scheme used
// ("<target>.tmp-<pid>-<n>", pids being guessable) and at the targets themselves: a bake's EXR set
// and render --out (EXR and PNG) write their files and leave the outside file as it was. Every
// other writer goes through the same files.h path (test_atomic_file.cpp).
// Inputs that never end (issue 45, point 3): a FIFO with no writer, /dev/zero, and a link to a FIFO,
// as the image of every command, as --gloss and as --manifest, are refused at once in one line
// naming what they are (each hung until killed: opening a FIFO blocks, /dev/zero never ends).
TEST(CliHostile, InputsThatNeverEndAreRefusedInOneLine) {
    TempDir dir;
    const fs::path fifo = dir / "map.png";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    fs::create_symlink(fifo, dir / "link.png");
    const std::string map = shellQuote(BURNISH_TEST_DATA_DIR "/trak-rust1_nm.png");
    for (const fs::path& input : {fifo, dir / "link.png", fs::path("/dev/zero")}) {
        const std::string in = shellQuote(input.string()), out = shellQuote((dir / "out").string());
        const char* kind = input == "/dev/zero" ? "a character device" : "a FIFO";
        for (const std::string& args :
             {"bake " + in + " --preset gltf --out " + out, "render " + in + " --out " + out + ".png",
              "evaluate " + in, "env " + in + " --out " + out, "gltf " + in + " --out " + out,
              "bake " + map + " --gloss " + in + " --preset blackops --out " + out,
              "bake --manifest " + in}) {
            SCOPED_TRACE(args);
            ::setenv("ASAN_OPTIONS", "detect_leaks=0", 1);
            const CliResult r = burnish::test::runBurnish(args, "", 20);
            EXPECT_NE(r.exitCode, 124) << "it hung";
            EXPECT_NE(r.exitCode, 0);
            EXPECT_EQ(lineCount(r.err), 1) << r.err;
            EXPECT_NE(r.err.find(kind), std::string::npos) << r.err;
            EXPECT_NE(r.err.find("not a regular file"), std::string::npos) << r.err;
        }
    }
    EXPECT_FALSE(fs::exists(dir / "out")) << "nothing written";
}

// A path holding a line break or an escape sequence is printed escaped (issue 45, point 8): the error
// stays one line and the terminal is never driven by a file's name.
TEST(CliHostile, ControlCharactersInPathsArePrintedEscaped) {
    TempDir dir;
    const std::string broken = (dir / "a\nb.png").string(), coloured = (dir / "c\x1b[31m.png").string();
    fs::copy_file(BURNISH_TEST_DATA_DIR "/trak-rust1_nm.png", coloured);
    for (const std::string& args :
         {"bake " + shellQuote(broken) + " --preset gltf --out " + shellQuote((dir / "out").string()),
          "bake " + shellQuote(coloured) + " --preset gltf --format nope --out " +
              shellQuote((dir / "o").string()),
          "render " + shellQuote(coloured) + " --mesh " + shellQuote(broken) + " --out " +
              shellQuote((dir / "x.png").string())}) {
        SCOPED_TRACE(args);
        const CliResult r = runBurnish(args);
        EXPECT_NE(r.exitCode, 0);
        EXPECT_EQ(lineCount(r.err), 1) << r.err;
        EXPECT_EQ(r.err.find('\x1b'), std::string::npos) << "a raw escape";
    }
    const CliResult missing = runBurnish("bake " + shellQuote(broken) + " --preset gltf --out " +
                                         shellQuote((dir / "out").string()));
    EXPECT_NE(missing.err.find("a\\nb.png"), std::string::npos) << missing.err;
}

// Huge finite numbers are refused by their option's range, not drawn wrong (issue 45, point 6):
// --yaw 1e308 drew a black image and exited 0; --light-dir=1e20,0,0 and =-1e20,0,0 drew the same.
TEST(CliHostile, HugeAnglesAndDirectionsAreRefusedByTheirRange) {
    TempDir dir;
    const std::string render = "render --size 8x8 --out " + shellQuote((dir / "x.png").string()) + " ";
    for (const std::string option : {"--yaw 1e308", "--yaw -1e30", "--yaw 36001", "--light-dir=1e20,0,0",
                                     "--light-dir=-1e20,0,0", "--light-dir=0,0,1e7"}) {
        SCOPED_TRACE(option);
        const CliResult r = runBurnish(render + option);
        EXPECT_NE(r.exitCode, 0);
        EXPECT_EQ(lineCount(r.err), 1) << r.err;
        EXPECT_NE(r.err.find("not in range"), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(dir / "x.png"));
    }
    // Inside the ranges: drawn.
    const CliResult turned = runBurnish(render + "--yaw 720 --light-dir=1e6,1,0");
    EXPECT_EQ(turned.exitCode, 0) << turned.err;
}

TEST(CliHostile, PlantedLinksAreNeverWrittenThrough) {
    TempDir dir;
    const fs::path outside = dir / "outside";
    const fs::path shared = dir / "shared";
    fs::create_directories(outside);
    fs::create_directories(shared);
    const fs::path victim = outside / "victim.txt";
    std::ofstream(victim) << "precious";
    // The pids the next processes are likely to get, and a counter range.
    const int next = int(::getpid());
    auto plant = [&](const std::string& target) {
        for (int pid = next; pid < next + 400; ++pid)
            for (int n = 0; n < 4; ++n)
                fs::create_symlink(
                    victim, shared / (target + ".tmp-" + std::to_string(pid) + "-" + std::to_string(n)));
        fs::create_symlink(victim, shared / target);
    };
    for (const char* name :
         {"trak-rust1_nm_normal.exr", "trak-rust1_nm_roughness.exr", "bake.json", "shot.exr", "shot.png"})
        plant(name);
    const std::string input = shellQuote(std::string(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png");
    const CliResult bake =
        runBurnish("bake " + input + " --preset godot --format exr-half --mips 2 --force --out " +
                   shellQuote((shared).string()) + " --power 256");
    ASSERT_EQ(bake.exitCode, 0) << bake.err;
    // --force: a link at the target itself is replaced (never followed) only when replacing is asked.
    const CliResult render = runBurnish("render --sample bumpy --sample-size 32 --size 32x32 --force --out " +
                                        shellQuote((shared / "shot.exr").string()));
    ASSERT_EQ(render.exitCode, 0) << render.err;
    const CliResult renderPng =
        runBurnish("render --sample bumpy --sample-size 32 --size 32x32 --force --out " +
                   shellQuote((shared / "shot.png").string()));
    ASSERT_EQ(renderPng.exitCode, 0) << renderPng.err;

    std::ifstream in(victim);
    std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(content, "precious");
    for (const char* name :
         {"trak-rust1_nm_normal.exr", "trak-rust1_nm_roughness.exr", "bake.json", "shot.exr", "shot.png"}) {
        EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(shared / name))) << name;
    }
    const auto image = burnish::readImage(shared / "trak-rust1_nm_roughness.exr");
    ASSERT_TRUE(image) << image.error();
    EXPECT_EQ(image->width, 512);
    for (const auto& e : fs::directory_iterator(shared))
        EXPECT_NE(e.path().filename().string().rfind(burnish::kStagingPrefix, 0), 0u) << e.path();
}

// bake --encoding overrides the detection (a signed map written as float with its negative values).
TEST(CliHostile, BakeEncodingOverridesDetection) {
    TempDir dir;
    // An unsigned float map (2v - 1 codes) with one -Inf texel: auto detection stays unsigned.
    std::vector<float> px;
    for (int i = 0; i < 64; ++i) {
        // Normals tilted by 0.3 or 0.25 in x and y and their mirror images, stored (v + 1) / 2.
        const float t = i % 3 ? 0.3f : 0.25f;
        const float sx = i % 2 ? t : -t, sy = (i / 2) % 2 ? t : -t;
        px.insert(px.end(),
                  {0.5f + 0.5f * sx, 0.5f + 0.5f * sy, 0.5f + 0.5f * std::sqrt(1.0f - 2.0f * t * t)});
    }
    px[9] = -std::numeric_limits<float>::infinity();
    ASSERT_TRUE(burnish::writeImageAtomic(dir / "n.exr", 8, 8, 3, px, {burnish::StoredType::Float, {}, {}}));
    const CliResult autoBake = runBurnish("bake " + shellQuote((dir / "n.exr").string()) +
                                          " --preset godot --json --out " + shellQuote((dir / "a").string()));
    ASSERT_EQ(autoBake.exitCode, 0) << autoBake.err;
    EXPECT_NE(autoBake.err.find("NaN or infinite"), std::string::npos) << autoBake.err;
    const auto bakeJson = nlohmann::json::parse(std::ifstream(dir / "a" / "bake.json"));
    EXPECT_FALSE(bakeJson["diagnostics"]["signedValues"].get<bool>());
    EXPECT_EQ(bakeJson["options"]["encoding"], "auto");
    // Forced signed: the same values read as stored are vectors of length about 1.3, which the
    // plausibility check refuses and --allow-implausible bakes as signed.
    const CliResult forced =
        runBurnish("bake " + shellQuote((dir / "n.exr").string()) +
                   " --preset godot --encoding signed --out " + shellQuote((dir / "s").string()));
    EXPECT_NE(forced.exitCode, 0);
    EXPECT_NE(forced.err.find("length"), std::string::npos) << forced.err;
    const CliResult allowed =
        runBurnish("bake " + shellQuote((dir / "n.exr").string()) + " --preset godot --encoding signed " +
                   "--allow-implausible --out " + shellQuote((dir / "s").string()));
    ASSERT_EQ(allowed.exitCode, 0) << allowed.err;
    const auto signedJson = nlohmann::json::parse(std::ifstream(dir / "s" / "bake.json"));
    EXPECT_TRUE(signedJson["diagnostics"]["signedValues"].get<bool>());
    EXPECT_EQ(signedJson["options"]["encoding"], "signed");
    const CliResult bad =
        runBurnish("bake " + shellQuote((dir / "n.exr").string()) +
                   " --preset godot --encoding sideways --out " + shellQuote((dir / "x").string()));
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_EQ(lineCount(bad.err), 1) << bad.err;
}

// `burnish bake --force` killed (SIGKILL, through BURNISH_FAULT_KILL_AT_COMMIT_STEP) at every step
// of the commit that replaces a TGA set with a PNG set: a bake.json in the folder always names a
// whole set (the old one before the first rename, the new one after the last), and recovering the
// folder (what the next export into it does first) leaves exactly what an uninterrupted bake
// leaves, byte for byte.
TEST(CliHostile, AKilledCommitIsFinishedByTheNextRun) {
    TempDir dir;
    std::vector<float> px;
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 40; ++x)
            px.insert(px.end(), {0.5f + 0.2f * std::sin(0.3f * float(x)),
                                 0.5f + 0.2f * std::cos(0.4f * float(y)), 0.95f});
    const fs::path map = dir / "map.png";
    ASSERT_TRUE(burnish::writeImageAtomic(map, 40, 24, 3, px, {burnish::StoredType::UInt8, {}, {}}));
    auto bake = [&](const fs::path& out, const char* format) {
        return runBurnish("bake " + shellQuote(map.string()) +
                          " --preset godot --power 256 --force --format " + format + " --out " +
                          shellQuote(out.string()));
    };
    auto list = [](const fs::path& folder) {
        std::set<std::string> names;
        for (const auto& e : fs::directory_iterator(folder))
            names.insert(e.path().filename().string());
        return names;
    };
    auto slurp = [](const fs::path& path) {
        std::ifstream in(path, std::ios::binary);
        return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    };
    const fs::path oldSet = dir / "old", newSet = dir / "new";
    ASSERT_EQ(bake(oldSet, "tga").exitCode, 0);
    ASSERT_EQ(bake(newSet, "tga").exitCode, 0);
    ASSERT_EQ(bake(newSet, "png8").exitCode, 0);
    const auto expected = list(newSet);
    ASSERT_EQ(expected.size(), 13u); // 6 levels of two files, bake.json

    int kills = 0;
    for (int step = 1;; ++step) {
        SCOPED_TRACE("killed after step " + std::to_string(step));
        const fs::path out = dir / ("run" + std::to_string(step));
        fs::copy(oldSet, out);
        ::setenv("BURNISH_FAULT_KILL_AT_COMMIT_STEP", std::to_string(step).c_str(), 1);
        const CliResult r = bake(out, "png8");
        ::unsetenv("BURNISH_FAULT_KILL_AT_COMMIT_STEP");
        if (r.exitCode == 0) break; // the commit has fewer steps: it ran to its end
        ++kills;
        if (fs::exists(out / "bake.json")) {
            const std::string index = slurp(out / "bake.json");
            EXPECT_TRUE(index == slurp(oldSet / "bake.json") || index == slurp(newSet / "bake.json"));
            if (index == slurp(oldSet / "bake.json")) {
                for (const auto& name : list(oldSet))
                    EXPECT_EQ(slurp(out / name), slurp(oldSet / name)) << name;
            }
        }
        const burnish::StagingRecovery recovered = burnish::recoverStaging(out);
        EXPECT_EQ(recovered.commitsFinished, 1);
        EXPECT_EQ(list(out), expected);
        for (const auto& name : expected)
            EXPECT_EQ(slurp(out / name), slurp(newSet / name)) << name;
        fs::remove_all(out);
    }
    // journal, old bake.json, 12 renames, 12 old TGA levels removed, bake.json
    EXPECT_EQ(kills, 27);
}

// A 200-byte PNG whose header claims 30000² texels (below the 2^30-texel limit): the bake's memory
// need (about 25 GB at godot) is checked against what may be used (8 GB here, by BURNISH_MEMORY_LIMIT:
// a machine with more would rightly go on to decode it) before anything is allocated, and refused with
// the size and the need in one line, at once.
TEST(CliHostile, ABakeThatCannotFitIsRefusedBeforeAllocating) {
    TempDir dir;
    writeClaimingPng(dir / "claims-huge.png", 30000);
    const CliResult r = runBurnish("bake " + shellQuote((dir / "claims-huge.png").string()) +
                                       " --preset godot --out " + shellQuote((dir / "out").string()),
                                   "BURNISH_MEMORY_LIMIT=8G");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(lineCount(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("30000x30000"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("needs about"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out" / "bake.json"));
}

// One memory ceiling for every command (issue 45, point 2): bake, render, evaluate and env estimate
// their need from the inputs' headers and the options and refuse, before decoding anything, in one line
// that gives the need and what may be used (BURNISH_MEMORY_LIMIT caps it, as on a shared farm node). A
// 16384² map claimed by a 200-byte file is refused by each command as too big, never decoded (it would
// be found cut short); an --face-size of 16384 likewise; a --detail map's memory counts; a --gloss map of
// another size is refused from its header; an unreadable limit is an error.
TEST(CliHostile, EveryCommandChecksItsMemoryBeforeReading) {
    TempDir dir;
    const fs::path huge = dir / "claims-16384.png";
    writeClaimingPng(huge, 16384);
    const std::string map = shellQuote(BURNISH_TEST_DATA_DIR "/trak-rust1_nm.png");
    const std::string big = shellQuote(huge.string()), out = shellQuote((dir / "out").string());
    auto refused = [&](const std::string& args, const std::string& limit, const std::string& what) {
        SCOPED_TRACE(args + " with BURNISH_MEMORY_LIMIT=" + limit);
        const CliResult r = runBurnish(args, "BURNISH_MEMORY_LIMIT=" + limit);
        EXPECT_NE(r.exitCode, 0);
        EXPECT_EQ(lineCount(r.err), 1) << r.err;
        EXPECT_NE(r.err.find("needs about"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("are available"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
        EXPECT_EQ(r.err.find("truncated"), std::string::npos) << "decoded before the check: " << r.err;
        EXPECT_FALSE(fs::exists(dir / "out")) << "nothing written";
    };
    // A small map under a small limit.
    refused("bake " + map + " --preset gltf --out " + out, "10M", "10 MB are available");
    refused("render " + map + " --out " + out + ".png", "100M", "rendering a 512x512 map at 512x512");
    refused("evaluate " + map + " --json", "100M", "evaluating a 512x512 map");
    refused("env --out " + out, "100M", "an environment cube of face size 256");
    // What claims more than a big machine holds.
    refused("bake " + big + " --preset gltf --out " + out, "4G", "16384x16384");
    refused("render " + big + " --out " + out + ".png", "16G", "rendering a 16384x16384 map");
    refused("evaluate " + big + " --json", "16G", "evaluating a 16384x16384 map");
    refused("env --face-size 16384 --out " + out, "16G", "face size 16384");
    refused("bake " + map + " --preset godot --detail " + big + " --out " + out, "16G", "512x512");
    // The same bake without the detail map fits.
    const CliResult fits =
        runBurnish("bake " + map + " --preset godot --out " + out, "BURNISH_MEMORY_LIMIT=16G");
    EXPECT_EQ(fits.exitCode, 0) << fits.err;
    fs::remove_all(dir / "out");

    const CliResult gloss = runBurnish("bake " + map + " --preset blackops --gloss " + big + " --out " + out);
    EXPECT_NE(gloss.exitCode, 0);
    EXPECT_EQ(lineCount(gloss.err), 1) << gloss.err;
    EXPECT_NE(gloss.err.find("gloss map is 16384x16384 but the normal map is 512x512"), std::string::npos)
        << gloss.err;
    EXPECT_FALSE(fs::exists(dir / "out"));

    for (const std::string limit : {"lots", "-5G", "6T", "99999999999999999999", "5G5"}) {
        const CliResult r = runBurnish("evaluate " + map + " --json", "BURNISH_MEMORY_LIMIT=" + limit);
        EXPECT_NE(r.exitCode, 0) << limit;
        EXPECT_EQ(lineCount(r.err), 1) << r.err;
        EXPECT_NE(r.err.find("BURNISH_MEMORY_LIMIT"), std::string::npos) << r.err;
    }
}

// `burnish env --force` killed at every step of its set's commit (the 8² set of DDS and EXR files
// replaced by a 4² EXR set): an env.json in the folder names a whole set, and recovery leaves
// exactly what an uninterrupted run leaves, byte for byte.
TEST(CliHostile, AKilledEnvironmentCommitIsFinishedByTheNextRun) {
    TempDir dir;
    auto slurp = [](const fs::path& path) {
        std::ifstream in(path, std::ios::binary);
        return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    };
    auto list = [](const fs::path& folder) {
        std::set<std::string> names;
        for (const auto& e : fs::directory_iterator(folder))
            names.insert(e.path().filename().string());
        return names;
    };
    const fs::path oldSet = dir / "old", newSet = dir / "new";
    ASSERT_EQ(runBurnish("env --face-size 8 --out " + shellQuote(oldSet.string())).exitCode, 0);
    const std::string newArgs = "env --face-size 4 --format exr --force --out ";
    ASSERT_EQ(runBurnish(newArgs + shellQuote(newSet.string())).exitCode, 0);
    const auto expected = list(newSet);
    int kills = 0;
    for (int step = 1; step < 200; ++step) {
        SCOPED_TRACE("killed after step " + std::to_string(step));
        const fs::path out = dir / ("run" + std::to_string(step));
        fs::copy(oldSet, out);
        ::setenv("BURNISH_FAULT_KILL_AT_COMMIT_STEP", std::to_string(step).c_str(), 1);
        const CliResult r = runBurnish(newArgs + shellQuote(out.string()));
        ::unsetenv("BURNISH_FAULT_KILL_AT_COMMIT_STEP");
        if (r.exitCode == 0) break;
        ++kills;
        if (fs::exists(out / "env.json")) {
            const std::string index = slurp(out / "env.json");
            EXPECT_TRUE(index == slurp(oldSet / "env.json") || index == slurp(newSet / "env.json"));
        }
        EXPECT_EQ(burnish::recoverStaging(out).commitsFinished, 1);
        EXPECT_EQ(list(out), expected);
        for (const auto& name : expected)
            EXPECT_EQ(slurp(out / name), slurp(newSet / name)) << name;
        fs::remove_all(out);
    }
    EXPECT_GT(kills, 30); // journal, old env.json, 25 renames, the old set's DDS files, env.json
}

std::set<std::string> namesIn(const fs::path& folder) {
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(folder))
        names.insert(e.path().filename().string());
    return names;
}

// evaluate's report folder is one set with evaluate.json as its index and its error maps a set of
// their own: killed after any step of either commit, a folder that holds an evaluate.json holds
// exactly the report it belongs to (the old one or the new one, error maps included), and the next
// run leaves exactly the new report.
TEST(CliHostile, AKilledReportCommitNeverLeavesAMixedReport) {
    TempDir dir;
    auto tree = [](const fs::path& folder) {
        // path -> bytes; Burnish's staging folders and the writer lock a killed run leaves (the next run
        // removes both) left out
        std::map<std::string, std::string> files;
        for (auto it = fs::recursive_directory_iterator(folder); it != fs::recursive_directory_iterator();
             ++it) {
            const std::string name = it->path().filename().string();
            if (name.rfind(".burnish-staging-", 0) == 0) {
                it.disable_recursion_pending();
                continue;
            }
            if (name == burnish::kWriterLockName) continue;
            if (!it->is_regular_file()) continue;
            std::ifstream in(it->path(), std::ios::binary);
            files[fs::relative(it->path(), folder).string()] =
                std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        }
        return files;
    };
    std::vector<float> px;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            const float nx = 0.4f * std::sin(float(x)), ny = 0.3f * std::cos(float(2 * y + x));
            const float nz = std::sqrt(1.0f - nx * nx - ny * ny);
            px.insert(px.end(), {0.5f * nx + 0.5f, 0.5f * ny + 0.5f, 0.5f * nz + 0.5f});
        }
    ASSERT_TRUE(
        burnish::writeImageAtomic(dir / "bumpy.png", 32, 32, 3, px, {burnish::StoredType::UInt8, {}, {}}));
    const std::string map = shellQuote((dir / "bumpy.png").string());
    const std::string common = " --bake-runs 1 --methods naive,lean --first-mip 1 --last-mip 2 --error-maps";
    const fs::path oldSet = dir / "old", newSet = dir / "new";
    ASSERT_EQ(
        runBurnish("evaluate " + map + common + " --power 64 --out " + shellQuote(oldSet.string())).exitCode,
        0);
    const std::string newArgs = "evaluate " + map + common + " --power 256 --force --out ";
    ASSERT_EQ(runBurnish(newArgs + shellQuote(newSet.string())).exitCode, 0);
    const auto before = tree(oldSet), after = tree(newSet);
    ASSERT_TRUE(before.count("errors/lean-s64-mip2.exr") && after.count("errors/lean-s256-mip2.exr"));
    // A report as `ref` has it: the same files, the same error maps bit for bit, the same powers in
    // evaluate.json (its timings, and the plots and text that show them, differ from run to run).
    auto sameReport = [](const std::map<std::string, std::string>& found,
                         const std::map<std::string, std::string>& ref) {
        if (found.size() != ref.size()) return false;
        for (const auto& [name, bytes] : ref) {
            const auto it = found.find(name);
            if (it == found.end()) return false;
            if (name.rfind("errors/", 0) == 0 && it->second != bytes) return false;
        }
        const auto powers = [](const std::string& json) {
            return nlohmann::json::parse(json)["base_powers"];
        };
        return powers(found.at("evaluate.json")) == powers(ref.at("evaluate.json"));
    };
    int kills = 0;
    for (int step = 1; step < 100; ++step) {
        SCOPED_TRACE("killed after step " + std::to_string(step));
        const fs::path out = dir / ("run" + std::to_string(step));
        fs::copy(oldSet, out, fs::copy_options::recursive);
        ::setenv("BURNISH_FAULT_KILL_AT_COMMIT_STEP", std::to_string(step).c_str(), 1);
        const CliResult r = runBurnish(newArgs + shellQuote(out.string()));
        ::unsetenv("BURNISH_FAULT_KILL_AT_COMMIT_STEP");
        if (r.exitCode == 0) break;
        ++kills;
        const auto found = tree(out);
        if (found.count("evaluate.json")) {
            EXPECT_TRUE(sameReport(found, before) || sameReport(found, after)) << "a mixed report";
        }
        ASSERT_EQ(runBurnish(newArgs + shellQuote(out.string())).exitCode, 0);
        EXPECT_TRUE(sameReport(tree(out), after)) << "the next run leaves exactly the new report";
        fs::remove_all(out);
    }
    // The maps' journal, 4 renames and 4 removals; the report's journal, the old index, 3 renames
    // and the new index.
    EXPECT_GE(kills, 14);
}

// One rule for every command that writes: an existing output is replaced only with --force, and
// with it exactly the new set is left (render's file; env's set named by env.json; evaluate's
// report and its error maps).
TEST(CliHostile, EveryCommandReplacesOnlyWithForceAndLeavesExactlyTheNewSet) {
    TempDir dir;
    const std::string shot = shellQuote((dir / "shot.png").string());
    ASSERT_EQ(runBurnish("render --sample bumpy --sample-size 16 --size 16x16 --out " + shot).exitCode, 0);
    const auto before = fs::last_write_time(dir / "shot.png");
    const CliResult again = runBurnish("render --sample bumpy --sample-size 16 --size 24x24 --out " + shot);
    EXPECT_NE(again.exitCode, 0);
    EXPECT_EQ(lineCount(again.err), 1) << again.err;
    EXPECT_NE(again.err.find("--force"), std::string::npos) << again.err;
    EXPECT_EQ(fs::last_write_time(dir / "shot.png"), before);
    ASSERT_EQ(
        runBurnish("render --sample bumpy --sample-size 16 --size 24x24 --force --out " + shot).exitCode, 0);
    EXPECT_EQ(burnish::readImage(dir / "shot.png")->width, 24);

    // env: 16² faces (5 mips, EXR and DDS), then 4² faces as EXR only with --force.
    const std::string env = shellQuote((dir / "env").string());
    ASSERT_EQ(runBurnish("env --face-size 16 --report --directions 4 --out " + env).exitCode, 0);
    const auto big = namesIn(dir / "env");
    const CliResult refused = runBurnish("env --face-size 4 --out " + env);
    EXPECT_NE(refused.exitCode, 0);
    EXPECT_NE(refused.err.find("--force"), std::string::npos) << refused.err;
    EXPECT_EQ(namesIn(dir / "env"), big);
    ASSERT_EQ(runBurnish("env --face-size 4 --format exr --force --out " + shellQuote((dir / "env").string()))
                  .exitCode,
              0);
    ASSERT_EQ(
        runBurnish("env --face-size 4 --format exr --out " + shellQuote((dir / "fresh").string())).exitCode,
        0);
    EXPECT_EQ(namesIn(dir / "env"), namesIn(dir / "fresh"));
    EXPECT_LT(namesIn(dir / "env").size(), big.size());

    // evaluate: error maps at two powers, then at one with --force: only its maps are left.
    std::vector<float> px;
    for (int i = 0; i < 16 * 16; ++i)
        px.insert(px.end(),
                  {0.5f + 0.2f * std::sin(float(i)), 0.5f + 0.2f * std::cos(0.7f * float(i)), 0.95f});
    ASSERT_TRUE(
        burnish::writeImageAtomic(dir / "m.png", 16, 16, 3, px, {burnish::StoredType::UInt8, {}, {}}));
    const std::string eval = "evaluate " + shellQuote((dir / "m.png").string()) +
                             " --methods naive,lean --last-mip 2 --bake-runs 1 --error-maps --out " +
                             shellQuote((dir / "report").string());
    ASSERT_EQ(runBurnish(eval + " --power 64 256").exitCode, 0);
    EXPECT_EQ(namesIn(dir / "report" / "errors").size(), 8u); // 2 methods x 2 powers x 2 mips
    const CliResult again2 = runBurnish(eval + " --power 512");
    EXPECT_NE(again2.exitCode, 0);
    EXPECT_NE(again2.err.find("--force"), std::string::npos) << again2.err;
    ASSERT_EQ(runBurnish(eval + " --power 512 --force").exitCode, 0);
    const auto maps = namesIn(dir / "report" / "errors");
    EXPECT_EQ(maps.size(), 4u);
    for (const auto& name : maps)
        EXPECT_NE(name.find("-s512-"), std::string::npos) << name;
}

bool allFinite(const nlohmann::json& j) {
    if (j.is_number_float()) return std::isfinite(j.get<double>());
    if (j.is_structured()) {
        for (const auto& v : j)
            if (!allFinite(v)) return false;
    }
    return true;
}

// Error maps, the JSON report and the Markdown of real maps hold no NaN or infinity, down to a
// sharp lobe (s = 10^5) on the map's steepest texels.
TEST(CliHostile, EvaluateOutputsAreFiniteOnRealMaps) {
    TempDir dir;
    // The real map's top-left 128² (the whole map takes long under the sanitizers).
    const auto full = burnish::readImage(std::string(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png");
    ASSERT_TRUE(full) << full.error();
    constexpr int kCrop = 128;
    std::vector<float> crop;
    for (int y = 0; y < kCrop; ++y)
        for (int x = 0; x < kCrop; ++x)
            for (int c = 0; c < 3; ++c)
                crop.push_back(
                    full->pixels[(size_t(y) * size_t(full->width) + size_t(x)) * size_t(full->channels) +
                                 size_t(c)]);
    ASSERT_TRUE(burnish::writeImageAtomic(dir / "crop.png", kCrop, kCrop, 3, crop,
                                          {burnish::StoredType::UInt8, {}, {}}));
    const CliResult r = runBurnish("evaluate " + shellQuote((dir / "crop.png").string()) +
                                   " --power 64 100000 --last-mip 3 --error-maps --bake-runs 1 --out " +
                                   shellQuote((dir / "report").string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto report = nlohmann::json::parse(std::ifstream(dir / "report" / "evaluate.json"));
    EXPECT_TRUE(allFinite(report));
    std::ifstream md(dir / "report" / "evaluate.md");
    const std::string text((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
    for (const char* word : {"nan", "inf", "NaN", "Inf"})
        EXPECT_EQ(text.find(std::string(" ") + word), std::string::npos) << word;
    int maps = 0;
    float worst = 0.0f;
    for (const auto& e : fs::recursive_directory_iterator(dir / "report")) {
        if (e.path().extension() != ".exr") continue;
        const auto image = burnish::readImage(e.path());
        ASSERT_TRUE(image) << image.error();
        for (float v : image->pixels)
            ASSERT_TRUE(std::isfinite(v) && v >= 0.0f && v < 1e6f) << e.path() << " " << v;
        for (float v : image->pixels)
            worst = std::max(worst, v);
        ++maps;
    }
    EXPECT_GT(maps, 10);
    std::printf("worst per-texel relative error: %g\n", double(worst));
}

} // namespace
