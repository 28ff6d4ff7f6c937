# shot.mk: make targets of one shot, one file per frame and stage. Frames are independent
# after the simulation, so `make -j` (or scripts/farm.sh over several machines) runs them in
# parallel, and make re-runs only what is stale:
#
#   particles/particles_NNNN.ply -> surface/surface_NNNN.ply -> spiky/spiky_NNNN.ply
#     -> shot/mesh_NNNN.inc (+ magnets_NNNN.inc) -> png/frame_NNNN.png -> shot.mp4, shot.gif
#
# A re-simulation rewrites every frame, but a frame whose new particle file has the same bytes
# as the previous run's keeps the previous file's time (see particles/.complete), so its
# meshes and render are not redone: extending [shot] duration, or a magnet edit that takes
# effect from frame N on, re-meshes only the frames whose particles changed.
#
# Every stage also depends on a stamp of the scene keys it reads, .scene/<stage>.toml,
# rewritten (at every make run) only when one of those values changes: editing [render]
# re-exports and re-renders every frame but re-meshes none, editing [surface] re-meshes,
# editing [sim] or the magnets re-simulates. Editing shot/look.inc re-renders.
#
# OUTDIR/Makefile, written by scripts/shot.sh, sets these and includes this file:
#   SCENE        scene file (absolute path)
#   FERRO_BIN    directory of the ferro-* executables (absolute path)
#   SHOT_FIRST, SHOT_LAST   the shot's frames (the range of shot/shot.ini and of the video)
#   SPIKES       1: run ferro-spikes between ferro-surface and ferro-pov; 0: export the surface
#   MAX_FRAMES   optional: simulate only up to this frame (ferro-sim --max-frames)
#   SIM_ELSEWHERE  1: the particle files come from a simulation run outside make (Slurm)
#   THREADS      optional: worker threads of each per-frame stage (default: all cores)
#   SETS         optional: scene overrides for every stage, words --set=section.key=value (a
#                preset and shot.sh's --set); each stage's stamp shows the values after them
#
# Targets (run in OUTDIR, or make -C OUTDIR ...):
#   make -j2                     everything: all frames up to PNG, then the video
#   make -j2 FIRST=10 LAST=20    frames 10..20 up to PNG (target `frames`)
#   make prepare                 the simulation and the shot files (shot.pov, .ini, look.inc)
#   make video                   shot.mp4 and shot.gif from png/ (needs ffmpeg)
#   make clean-renders           delete the PNGs (keeps particles and meshes)

SHELL := /bin/bash
# This file's directory (scripts/): its helper frame-unchanged.sh lives beside it.
SHOT_SCRIPTS := $(patsubst %/,%,$(dir $(lastword $(MAKEFILE_LIST))))
.DELETE_ON_ERROR:
.SUFFIXES:
# Intermediate files (meshes between stages) are kept: they are the point of the pipeline.
.SECONDARY:

SHOT_FIRST ?= 0
FIRST ?= $(SHOT_FIRST)
LAST ?= $(SHOT_LAST)
SPIKES ?= 0
POVRAY ?= povray
FFMPEG ?= ffmpeg
# Extra POV-Ray options for every frame, e.g. POVRAY_ARGS='+W320 +H240' for a preview.
POVRAY_ARGS ?=
# Worker threads of each per-frame stage (empty: all cores). A scheduler's task sets it to
# the cores it was given.
THREADS ?=
threads_arg = $(if $(THREADS),--threads $(THREADS))

SETS ?=

FRAMES := $(shell seq -f %04g $(FIRST) $(LAST))
SHOT_FRAMES := $(shell seq -f %04g $(SHOT_FIRST) $(SHOT_LAST))

# ---- Scene stamps ---------------------------------------------------------------------------
# A stage's stamp is what the stage itself says it reads: `--print-scene-inputs` makes it
# parse the scene (with SETS applied) and print every key its parser looked up, with its
# value or "(absent)". There is no second list of which stage reads what to go stale: a key a
# parser starts to read is in that stage's stamp from then on. A scene that does not parse
# stops make here with the stage's own one-line error (the frames made so far are untouched).
# $(call scene_stamp,name,command,extra line): refresh .scene/name.toml if its text changed.
scene_stamp = $(shell mkdir -p .scene && t=.scene/.$(1).$$$$ && \
  if { $(2) && echo '$(3)'; } > $$t; then \
    if cmp -s $$t .scene/$(1).toml; then rm -f $$t; else mv -f $$t .scene/$(1).toml; fi; \
  else rm -f $$t; echo failed; fi)
stamp_or_stop = $(if $(call scene_stamp,$(1),$(2),$(3)),$(error shot.mk: cannot read the scene for the $(1) stage (see the line above)))
$(call stamp_or_stop,sim,$(FERRO_BIN)/ferro-sim '$(SCENE)' --print-scene-inputs $(SETS),max_frames=$(MAX_FRAMES))
$(call stamp_or_stop,surface,$(FERRO_BIN)/ferro-surface --scene '$(SCENE)' --print-scene-inputs $(SETS),)
# (ferro-spikes may not be built: shot.sh then sets SPIKES=0 and nothing needs its stamp.)
ifeq ($(SPIKES),1)
$(call stamp_or_stop,spikes,$(FERRO_BIN)/ferro-spikes --scene '$(SCENE)' --print-scene-inputs $(SETS),)
endif
$(call stamp_or_stop,export,$(FERRO_BIN)/ferro-pov --scene '$(SCENE)' --no-shot --print-scene-inputs $(SETS),)
$(call stamp_or_stop,render,$(FERRO_BIN)/ferro-pov --scene '$(SCENE)' --shot-frames $(SHOT_FIRST):$(SHOT_LAST) --print-scene-inputs $(SETS),shot_frames=$(SHOT_FIRST):$(SHOT_LAST))

# 0010 -> 10 (a leading zero would read as octal to some parsers).
frame_number = $$((10\#$(1)))

.PHONY: all frames prepare video clean-renders
all: frames $(if $(shell command -v $(FFMPEG)),video)
frames: $(FRAMES:%=png/frame_%.png)
prepare: particles/.complete shot/shot.pov shot/look.inc

# ---- Simulation: one run writes every frame ---------------------------------------------------
# Into particles.new/, swapped in only when the run succeeded: a failed or interrupted
# re-simulation (after a [sim] edit) keeps the previous frames and everything made from them.
# The settled pre-roll ([shot] preroll) is cached beside it in preroll.ply: ferro-sim reuses
# it while the sections it depends on are unchanged (an edit of later magnet keys re-runs the
# shot but not the pre-roll).
# Frames where nothing moved: before the swap, every new frame file that holds the same frame
# as the previous run's file of that number (scripts/frame-unchanged.sh: every particle value
# and every header line bit for bit, except the lines naming the run's scene and its hash;
# exact, no tolerance) is given the previous file's time (touch -r), so make sees it as old and
# keeps its meshes and render; a frame where anything changed keeps the time ferro-sim wrote
# it, newer than every mesh made before, and is re-meshed. The line `shot.mk: frames
# unchanged: K of N` says how many frames kept their meshes.
particles/.complete: .scene/sim.toml
	rm -rf particles.new
	$(FERRO_BIN)/ferro-sim '$(SCENE)' --out particles.new --preroll-cache preroll.ply --quiet $(if $(MAX_FRAMES),--max-frames $(MAX_FRAMES)) $(SETS)
	@same=0 all=0; for f in particles.new/particles_*.ply; do [ -e "$$f" ] || continue; all=$$((all + 1)); \
	  old=particles/$${f##*/}; if '$(SHOT_SCRIPTS)/frame-unchanged.sh' "$$old" "$$f"; then touch -r "$$old" "$$f"; same=$$((same + 1)); fi; \
	done; echo "shot.mk: frames unchanged: $$same of $$all (the same as the previous run's: not re-meshed)"
	touch particles.new/.complete
	rm -rf particles.old
	if [ -d particles ]; then mv particles particles.old; fi
	mv particles.new particles
	rm -rf particles.old

# A particle file is made by the simulation (an order-only prerequisite: the file's own time,
# set above, says whether it changed). A frame the simulation never reached is an error, not
# an empty frame. With SIM_ELSEWHERE=1 (a Slurm frame task: scripts/slurm/) another job runs
# the simulation and publishes each frame when it is complete, so a frame never waits for
# the whole run, and never starts one.
ifeq ($(SIM_ELSEWHERE),1)
particles/particles_%.ply:
	@test -f $@ || { echo "shot.mk: $@ is missing: the simulation job has not published frame $*" >&2; exit 1; }
else
particles/particles_%.ply: | particles/.complete
	@test -f $@ || { echo "shot.mk: $@ is missing: the simulation stopped before frame $*" >&2; exit 1; }
endif

# ---- Per frame ----------------------------------------------------------------------------------
surface/surface_%.ply: particles/particles_%.ply .scene/surface.toml
	@mkdir -p surface
	$(FERRO_BIN)/ferro-surface $< --scene '$(SCENE)' --out $@ --quiet $(threads_arg) $(SETS)

spiky/spiky_%.ply: surface/surface_%.ply particles/particles_%.ply .scene/spikes.toml
	@mkdir -p spiky
	$(FERRO_BIN)/ferro-spikes $< --particles particles/particles_$*.ply --particle-history 'particles/particles_{:04}.ply' --scene '$(SCENE)' --out $@ --quiet $(threads_arg) $(SETS)

ifeq ($(SPIKES),1)
EXPORTED_MESH := spiky/spiky_%.ply
else
EXPORTED_MESH := surface/surface_%.ply
endif

# Both includes come from one ferro-pov run (a grouped pattern rule).
shot/mesh_%.inc shot/magnets_%.inc: $(EXPORTED_MESH) .scene/export.toml
	$(FERRO_BIN)/ferro-pov $< --scene '$(SCENE)' --frame $(call frame_number,$*) --out shot --no-shot --quiet $(SETS)

# The shot files. ferro-pov rewrites shot.pov and the .ini files only when their text changes;
# the touch marks them as made from the current [render].
shot/shot.pov: .scene/render.toml
	$(FERRO_BIN)/ferro-pov --scene '$(SCENE)' --out shot --shot-frames $(SHOT_FIRST):$(SHOT_LAST) --quiet $(SETS)
	touch $@
# The look template is written only when missing; after that it is the artists' file.
shot/look.inc: | shot/shot.pov
	$(FERRO_BIN)/ferro-pov --scene '$(SCENE)' --out shot --shot-frames $(SHOT_FIRST):$(SHOT_LAST) --quiet $(SETS)

# With motion blur (render.motion_blur > 1, ferro-pov writes blur.ini) a frame is the mean of
# its sub-frames: blur.ini renders them into shot/sub/, average.ini averages them.
png/frame_%.png: shot/mesh_%.inc shot/magnets_%.inc shot/shot.pov shot/look.inc
	@mkdir -p png shot/log shot/sub
	cd shot && { if [ -f blur.ini ]; then \
	    $(POVRAY) blur.ini -D Declare=FerroFrame=$(call frame_number,$*) +Osub/frame_$*_.png \
	      $(if $(THREADS),+WT$(THREADS)) $(POVRAY_ARGS) && \
	    $(POVRAY) average.ini -D Declare=FerroFrame=$(call frame_number,$*) +O../png/.frame_$*.tmp.png \
	      $(if $(THREADS),+WT$(THREADS)) $(POVRAY_ARGS) +Q0 -A; \
	  else \
	    $(POVRAY) render.ini -D Declare=FerroFrame=$(call frame_number,$*) +O../png/.frame_$*.tmp.png \
	      $(if $(THREADS),+WT$(THREADS)) $(POVRAY_ARGS); \
	  fi; } > log/frame_$*.log 2>&1 \
	  || { tail -n 20 log/frame_$*.log >&2; rm -f ../png/.frame_$*.tmp.png sub/frame_$*_*.png; exit 1; }
	rm -f shot/sub/frame_$*_*.png
	mv -f png/.frame_$*.tmp.png $@

# ---- Video --------------------------------------------------------------------------------------
FPS = $(shell sed -n 's/^\#declare FerroFps = \(.*\);/\1/p' shot/shot.pov)
video: shot.mp4 shot.gif
shot.mp4: $(SHOT_FRAMES:%=png/frame_%.png)
	$(FFMPEG) -y -loglevel error -framerate $(FPS) -start_number $(SHOT_FIRST) -i png/frame_%04d.png \
	  -vf 'scale=trunc(iw/2)*2:trunc(ih/2)*2' -c:v libx264 -pix_fmt yuv420p -crf 20 .shot.tmp.mp4
	mv -f .shot.tmp.mp4 $@
shot.gif: $(SHOT_FRAMES:%=png/frame_%.png)
	$(FFMPEG) -y -loglevel error -framerate $(FPS) -start_number $(SHOT_FIRST) -i png/frame_%04d.png \
	  -vf 'fps=15,scale=min(iw\,480):-1:flags=lanczos,split[a][b];[a]palettegen=stats_mode=diff[p];[b][p]paletteuse=dither=bayer:bayer_scale=3' \
	  -loop 0 .shot.tmp.gif
	mv -f .shot.tmp.gif $@

clean-renders:
	rm -f png/frame_*.png shot.mp4 shot.gif
