#!/usr/bin/env bash
# One command for a GPU run: the figures this project quotes, measured on
# whatever adapter wgpu picks here, written as one markdown file under
# docs/runs/ (adapter, driver, every figure with its interval where the
# run has one). Needs only what the README's set-up installs (a Rust
# toolchain, a Vulkan/Metal/DX12 driver, Node.js for the table).
#
#   scripts/gpu-run.sh            # the full run
#   GPU_RUN_QUICK=1 scripts/gpu-run.sh   # a smoke run: small frames, few
#                                        # frames (to check the script)
#   GPU_RUN_REPRODUCTION=1 scripts/gpu-run.sh   # docs/reproduction.md's
#       experiments at 256² and 512² instead (below; about 65 minutes on
#       lavapipe, minutes on a GPU); GPU_RUN_EVERY_CANDIDATE=1 adds fig. 8
#       over all 459 candidates (about 50 minutes more on lavapipe);
#       GPU_RUN_EVERY_CANDIDATE=only runs that step alone
#   GPU_RUN_KEEP=DIR keeps every run's report folder in DIR (else only the
#       table under docs/runs/ remains)
#
# What it runs, in order (each a command of README.md or docs/):
#   1. README's two profiles: the environment map (its first command,
#      which pays) and the marble sphere (its second, which does not);
#   2. docs/results.md's headline: the profile at 256² and 512²;
#   2b. docs/results.md's upsampling tables (Herzog et al. 2010): every
#      reconstruction of the forward and the deferred lowres beside two-,
#      three-pass and deferred, on the environment map, the marble and the
#      64-tap blur, each at 256² and 512²;
#   3. Sitthi-amorn et al. 2008 fig. 8 at 1024×768: one-, two-, three-pass and deferred
#      for nodes spanning the marble's P/T range (one octave, the partial
#      octave sums, the turbulence's marble, the albedo, the lit colour),
#      Δn = 32, k = 4 (the paper's setting);
#   4. Sitthi-amorn et al. 2008 fig. 9 at 1024×768: Δn ∈ {8, 16, 32, 64} × k ∈ {1, 2, 4}
#      for every variant, with the paper's kind of node (two octaves of
#      noise, object-space: `s2`) and with the lit colour;
#   5. `interpolate` on every bundled interpolation scene at 256²;
#   6. docs/governor.md's `play` runs: the governor on a winning cache
#      (the environment map, two-pass) and a losing one (the marble,
#      three-pass at Δn = 1), and the error watch (its cost on the
#      environment map, and Δn lowered where a light starts to move), 256²;
#   7. docs/bevy.md's per-material figures (the Bevy example's measure
#      and compare on its game scene), beside the table.
# Budget: minutes on a discrete GPU; under an hour on lavapipe (2 cores).
#
# With GPU_RUN_REPRODUCTION=1 it runs docs/reproduction.md's experiments
# instead, at 256² and 512²: figs. 8 and 9 on the marble sphere and on the
# 77k-triangle torus (the paper's geometry load), fig. 8 over every fifth
# candidate of the marble (256², 16 frames), the 25-tap environment map
# on the heavy torus, and fig. 7's overlap outlier beside the partial
# octave sums of like P/T.
set -euo pipefail
cd "$(dirname "$0")/.."

quick=${GPU_RUN_QUICK:-}
if [ -n "$quick" ]; then
  big=128x96; small=64x64; mid=96x96; frames=(--frames 8 --warmup 8); iframes=(--frames 8)
  played=(--frames 60)
else
  big=1024x768; small=256x256; mid=512x512; frames=(--frames 32); iframes=()
  played=(--frames 1000)
fi

cargo build --release --locked -p shadecache-cli
bin=target/release/shadecache
work=$(mktemp -d)
# GPU_RUN_KEEP=DIR keeps every run's report (report.json, report.html,
# images) there, for what the table leaves out: the fig. 8 chart, the
# P/T bins of scripts/fig8-bins.mjs.
keep() {
  if [ -n "${GPU_RUN_KEEP:-}" ]; then
    mkdir -p "$GPU_RUN_KEEP" && cp -r "$work"/. "$GPU_RUN_KEEP"/ && echo "reports kept in $GPU_RUN_KEEP" >&2
  fi
  rm -rf "$work"
}
trap keep EXIT
manifest="$work/runs.tsv"
: > "$manifest"

# measure NAME ARGS...: one shadecache command into $work/NAME; its wall
# time in seconds in $elapsed.
measure() {
  local name=$1; shift
  local start
  start=$(date +%s)
  echo "== $name: shadecache $*" >&2
  "$bin" "$@" --out "$work/$name" --quiet > "$work/$name.log" 2>&1 || {
    echo "$name failed:" >&2; tail -20 "$work/$name.log" >&2; exit 1; }
  elapsed=$(( $(date +%s) - start ))
}

# run NAME ARGS...: `measure`, listed in the manifest with its command
# line and its wall time.
run() {
  local name=$1
  measure "$@"; shift
  printf '%s\t%s\t%s\n' "$name" "$elapsed" "shadecache $*" >> "$manifest"
}

marble=(corpus/noise_marble.wgsl --scene corpus/scenes/marble_sphere.toml)
# The marble's nodes across its P/T range (ids from `shadecache analyze
# corpus/noise_marble.wgsl`): one octave, the partial sums of two to five
# octaves, the marble stripes, the albedo, the lit colour.
one_octave=n04bcefa2
two_octaves=n6223a6b5
fig8_nodes=$one_octave,$two_octaves,n5913d8f1,nb4278c81,nb0c12cc4,n648ad2bd,nc36c801b,n5c3eb6af
lit=n5c3eb6af

if [ -n "${GPU_RUN_REPRODUCTION:-}" ]; then
  heavy=(corpus/noise_marble.wgsl --scene corpus/scenes/heavy_marble_torus.toml)
  envmap=(corpus/envmap_gauss.wgsl --scene corpus/scenes/heavy_envmap_torus.toml)
  # The lit colour's direct-light term: overlap 2977 of 3098 (fig. 7's
  # outliers have hits and misses both costly), beside the partial sums
  # of like P/T, which have none.
  overlapping=n75f9cb00
  sizes=("$small" "$mid")
  if [ "${GPU_RUN_EVERY_CANDIDATE:-}" = only ]; then sizes=(); fi
  for size in "${sizes[@]}"; do
    for scene in marble heavy; do
      declare -n args=$scene
      run "fig8-$scene-$size" profile "${args[@]}" --size "$size" "${frames[@]}" --nodes "$fig8_nodes" \
        --variant one-pass,two-pass,three-pass,deferred --refresh-period 32 --refresh-quad 4
      run "fig9-$scene-$size" profile "${args[@]}" --size "$size" "${frames[@]}" --nodes "$two_octaves,$lit" \
        --variant one-pass,two-pass,three-pass,deferred --refresh-period 8,16,32,64 --refresh-quad 1,2,4
      unset -n args
    done
    run "envmap-$size" profile "${envmap[@]}" --size "$size" "${frames[@]}" --nodes top:3 \
      --variant one-pass,two-pass,three-pass,deferred --refresh-period 32 --refresh-quad 4
    run "fig7-overlap-$size" profile "${marble[@]}" --size "$size" "${frames[@]}" \
      --nodes "$overlapping,nb4278c81,nb0c12cc4,n648ad2bd" \
      --variant one-pass,two-pass,three-pass,deferred --refresh-period 32 --refresh-quad 4
  done
  # Fig. 8 over the candidates: every fifth of the marble's 459 in their
  # ranking (92; a smoke run, every fifth of the first 60), every variant,
  # in one process.
  if [ "${GPU_RUN_EVERY_CANDIDATE:-}" != only ]; then
  ranked=$("$bin" analyze corpus/noise_marble.wgsl --format json | node -e '
    const c = JSON.parse(require("fs").readFileSync(0, "utf8")).candidates;
    const n = process.argv[1] ? Number(process.argv[1]) : c.length;
    console.log(c.slice(0, n).filter((_, i) => i % 5 === 0).map((x) => x.id).join(","));
  ' "${quick:+60}")
  run fig8-fifth-candidates profile "${marble[@]}" --size "$small" --frames 16 --nodes "$ranked" \
    --variant one-pass,two-pass,three-pass,deferred --refresh-period 32 --refresh-quad 4
  fi
  # Every candidate (GPU_RUN_EVERY_CANDIDATE=1): 1836 configurations and
  # six fixed-cost runs per node, more pipelines than lavapipe keeps in one
  # process's memory (a single run was killed at 24 GiB), so in shards
  # (`profile --shard K/N`: each a process with its own reference run,
  # setting up only the nodes of its contiguous slice) joined by
  # `shadecache merge`.
  if [ -n "${GPU_RUN_EVERY_CANDIDATE:-}" ]; then
    every=all; shards=6
    if [ -n "$quick" ]; then every=top:12; shards=2; fi
    all=(profile "${marble[@]}" --size "$small" --frames 16 --nodes "$every"
      --variant one-pass,two-pass,three-pass,deferred --refresh-period 32 --refresh-quad 4)
    total=0
    for k in $(seq 1 "$shards"); do
      measure "fig8-all-shard-$k" "${all[@]}" --shard "$k/$shards"
      total=$((total + elapsed))
    done
    "$bin" merge "$work"/fig8-all-shard-*/ --out "$work/fig8-all-candidates" > "$work/merge.log" 2>&1 || {
      echo "merge failed:" >&2; tail -20 "$work/merge.log" >&2; exit 1; }
    printf '%s\t%s\t%s\n' fig8-all-candidates "$total" \
      "shadecache ${all[*]} --shard K/$shards (K = 1..$shards), then shadecache merge of the $shards" >> "$manifest"
  fi
  mkdir -p docs/runs
  out=$(node scripts/runs-table.mjs "$work" "$manifest" ${quick:+--quick} --reproduction)
  echo "wrote $out" >&2
  exit 0
fi

envmap_sphere=(corpus/envmap_gauss.wgsl --scene corpus/scenes/envmap_sphere.toml)
run readme-first profile "${envmap_sphere[@]}" --max-error psnr:35 "${frames[@]}"
run readme-profile profile "${marble[@]}" "${frames[@]}"
run results-256 profile "${marble[@]}" --size "$small" "${frames[@]}"
run results-512 profile "${marble[@]}" --size "$mid" "${frames[@]}"
upsampling=(--variant two-pass,three-pass,deferred,lowres,deferred-lowres
  --lowres-reconstruction nearest,bilinear,spatial,temporal,spatio-temporal --nodes top:1)
run upsampling-envmap-256 profile "${envmap_sphere[@]}" --size "$small" "${frames[@]}" "${upsampling[@]}"
run upsampling-envmap-512 profile "${envmap_sphere[@]}" --size "$mid" "${frames[@]}" "${upsampling[@]}"
run upsampling-marble-256 profile "${marble[@]}" --size "$small" "${frames[@]}" "${upsampling[@]}"
run upsampling-marble-512 profile "${marble[@]}" --size "$mid" "${frames[@]}" "${upsampling[@]}"
# The heaviest payload of docs/results.md's lowres tables: the directional
# blur at 64 taps (the bundled scene's `sample_count = 8` set to 64), at a
# path the table's commands can name.
mkdir -p target/gpu-run
sed 's/sample_count = 8/sample_count = 64/' corpus/scenes/blurred_texture.toml > target/gpu-run/blur64.toml
blur64=(corpus/texture_loop.wgsl --scene target/gpu-run/blur64.toml)
run upsampling-blur64-256 profile "${blur64[@]}" --size "$small" "${frames[@]}" "${upsampling[@]}"
run upsampling-blur64-512 profile "${blur64[@]}" --size "$mid" "${frames[@]}" "${upsampling[@]}"
run fig8 profile "${marble[@]}" --size "$big" "${frames[@]}" --nodes "$fig8_nodes" \
  --variant one-pass,two-pass,three-pass,deferred --refresh-period 32 --refresh-quad 4
run fig9 profile "${marble[@]}" --size "$big" "${frames[@]}" --nodes "$two_octaves,$lit" \
  --variant one-pass,two-pass,three-pass,deferred --refresh-period 8,16,32,64 --refresh-quad 1,2,4
for scene in walking_floor globe windmill windmill_every_frame moving_light; do
  run "interpolate-$scene" interpolate corpus/noise_marble.wgsl --scene "corpus/scenes/$scene.toml" \
    --size "$small" "${iframes[@]}"
done
run interpolate-terrain_flyover interpolate corpus/terrain_slope_branch.wgsl \
  --scene corpus/scenes/terrain_flyover.toml --size "$small" "${iframes[@]}"
run play-envmap-two-pass play "${envmap_sphere[@]}" --size "$small" "${played[@]}" --variant two-pass
run play-marble-three-pass-every-frame play "${marble[@]}" --size "$small" "${played[@]}" \
  --variant three-pass --refresh-period 1
# The error watch: its cost on a winning cache, and Δn lowered where a
# light starts to move.
run play-envmap-two-pass-watched play "${envmap_sphere[@]}" --size "$small" "${played[@]}" \
  --variant two-pass --min-psnr 35
run play-light-starts-moving-watched play corpus/noise_marble.wgsl \
  --scene corpus/scenes/light_starts_moving.toml --size "$small" "${played[@]}" \
  --variant one-pass --refresh-period 16 --min-psnr 36

mkdir -p docs/runs
out=$(node scripts/runs-table.mjs "$work" "$manifest" ${quick:+--quick})
echo "wrote $out" >&2

# 7. docs/bevy.md's per-material figures: the Bevy example's game scene
#    with the lava, the StandardMaterial props and both cached, timed by
#    Bevy's render diagnostics, and each against Bevy's own frame, beside
#    the table (GPU_RUN_BEVY=0 leaves it out: it builds Bevy).
if [ "${GPU_RUN_BEVY:-1}" != 0 ]; then
  side=${small%%x*}
  if [ -n "$quick" ]; then bevy_frames=(16 16); else bevy_frames=(100 60); fi
  bevy_out="${out%.md}-bevy.txt"
  {
    echo "\$ cargo run --release -p shadecache-bevy-example -- measure --size $side --frames ${bevy_frames[0]}"
    cargo run --release --locked -q -p shadecache-bevy-example -- measure --size "$side" --frames "${bevy_frames[0]}"
    echo "\$ cargo run --release -p shadecache-bevy-example -- compare --size $side --frames ${bevy_frames[1]}"
    cargo run --release --locked -q -p shadecache-bevy-example -- compare --size "$side" --frames "${bevy_frames[1]}" \
      | grep -v "compared frame"
  } > "$bevy_out"
  echo "wrote $bevy_out" >&2
fi
