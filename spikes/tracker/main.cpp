// ferro-tips: finds the spike tips of a shot's spiky meshes and matches them frame to frame
// (how coherent the spikes are in motion). Parses arguments and calls the tracker library.
#include "sim/core/CommandLine.hpp"
#include "sim/core/ErrorText.hpp"
#include "sim/core/ExitCodes.hpp"
#include "sim/core/ParticleFile.hpp"
#include "spikes/tracker/TipTracker.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>

int main(int argc, char** argv) {
    using namespace ferro;
    CLI::App app{"ferro-tips: spike tips per frame and their frame-to-frame matches\n"
                 "  ferro-tips 'spiky/spiky_{:04}.ply' --surface 'surface/surface_{:04}.ply' --frames A:B [--csv FILE]"};
    std::string spiky, surface, frames, csv;
    TipFinderParams params;
    double gate = 0.5, edge = 0.25;
    app.add_option("spiky", spiky, "spiky mesh pattern (ferro-spikes output) with {:04} / %04d")->required();
    app.add_option("--surface", surface, "surface mesh pattern (the ferro-surface meshes the spikes were added to)")
        ->required();
    app.add_option("--frames", frames, "frame range A:B (inclusive)")->type_name("A:B")->required();
    app.add_option("--csv", csv, "write one row per frame step to this file");
    std::string tipsCsv;
    app.add_option("--tips", tipsCsv, "write every tip (frame, x, y, z [m], height [m]) to this file");
    app.add_option("--min-height", params.minHeight, "a tip stands at least this far out of the surface [m]")
        ->check(CLI::PositiveNumber);
    app.add_option("--gate", gate, "match tips closer than this many tip spacings (default 0.5)")
        ->check(CLI::PositiveNumber);
    bool noPredict = false;
    app.add_flag("--no-predict", noPredict,
                 "match by raw distance, not from where the neighbours' motion (scale and shift) puts a tip");
    app.add_option("--edge", edge, "born/died tips at least this fraction of the largest tip count as interior (0.25)")
        ->check(CLI::Range(0.0, 1.0));
    const std::vector<ErrorExit> errors = {exitOn<std::exception>(kExitFailure, "", oneLine)};
    return runCommandLine("ferro-tips", app, argc, argv, errors, [&] {
        const FrameRange range = frameRangeArgument("--frames", frames);
        const TipTrack track = trackTips(spiky, surface, range.first, range.last, params, gate, edge, !noPredict);
        const std::string table = tipTrackCsv(track);
        if (!csv.empty()) {
            std::ofstream out(csv);
            if (!(out << table)) throw MeshFileError(csv + ": cannot write", kExitIoError);
        }
        if (!tipsCsv.empty()) {
            std::ofstream out(tipsCsv);
            out << "frame,x,y,z,height\n";
            out.precision(9);
            for (size_t k = 0; k < track.tips.size(); ++k)
                for (const SpikeTipSample& t : track.tips[k])
                    out << track.first + int(k) << "," << t.position.x() << "," << t.position.y() << ","
                        << t.position.z() << "," << t.height << "\n";
            if (!out) throw MeshFileError(tipsCsv + ": cannot write", kExitIoError);
        }
        double worstStable = 1, worstInterior = 1, worstJump = 0;
        int interior = 0;
        for (const TipFrameMatch& m : track.steps) {
            worstStable = std::min(worstStable, m.stableFraction);
            worstInterior = std::min(worstInterior, m.interiorStableFraction);
            worstJump = std::max(worstJump, m.maxHeightJump);
            interior += m.interiorBorn + m.interiorDied;
        }
        std::cout << table;
        std::fprintf(stderr,
                     "ferro-tips: %zu steps: worst stable fraction %.3f (interior %.3f), largest height jump %.3f of the largest tip, "
                     "%d interior births/deaths\n",
                     track.steps.size(), worstStable, worstInterior, worstJump, interior);
        // Against the fluid under them (surface meshes with velocities and `time` headers):
        // over all compared tips of all steps, sum |v - u| / sum |u|.
        double sumU = 0, sumDiff = 0;
        int compared = 0;
        for (const TipFrameMatch& m : track.steps) {
            sumU += m.surfaceSpeed * m.flowTips;
            sumDiff += m.flowDifference * m.flowTips;
            compared += m.flowTips;
        }
        if (compared > 0 && sumU > 0)
            std::fprintf(stderr, "ferro-tips: %d tip moves against the surface under them: mean surface speed %.2f mm/s, "
                         "tips' velocity off it by %.3f of it (sum |v - u| / sum |u|)\n",
                         compared, 1e3 * sumU / compared, sumDiff / sumU);
        return kExitOk;
    });
}
