#!/usr/bin/env bash
# Bit-identity of scene loading across a change: renders every shipped scene and every scene of
# Mitsuba's render-test suite at 1 spp with `pt` by a baseline `lt` and by this tree's, and `cmp`s
# the EXRs; a scene either build refuses must be refused by both (the messages are shown). Also
# `lt convert`s every shipped TOML scene with both and diffs the XML.
# Not run by CI (a few minutes on one core). Usage, from the workspace root:
#   crates/scene-io/tests/bit_identity.sh [BASELINE_LT] [NEW_LT] [OUT_DIR]
set -u
base=${1:-/work/baseline/lt}
new=${2:-target/release/lt}
out=${3:-/tmp/lt-bit-identity}
suite=${SUITE:-/work/shared/mitsuba-render-tests/tests/scenes}
mkdir -p "$out/base" "$out/new"
scenes=$( (find scenes -name '*.toml' -o -name '*.xml'; [ -d "$suite" ] && find "$suite" -name '*.xml') | sort)
same=0; diff=0; refused=0
for s in $scenes; do
  key=$(echo "$s" | tr '/' '_')
  for side in base new; do
    bin=$base; [ $side = new ] && bin=$new
    if [ ! -e "$out/$side/$key.exr" ] && [ ! -e "$out/$side/$key.err" ] || [ $side = new ]; then
      rm -f "$out/$side/$key.exr" "$out/$side/$key.err"
      "$bin" render "$s" --spp 1 -i pt --approximate --threads 1 --quiet \
        -o "$out/$side/$key.exr" >/dev/null 2>"$out/$side/$key.log" \
        || cp "$out/$side/$key.log" "$out/$side/$key.err"
    fi
  done
  if [ -e "$out/base/$key.err" ] || [ -e "$out/new/$key.err" ]; then
    if [ -e "$out/base/$key.err" ] && [ -e "$out/new/$key.err" ]; then
      refused=$((refused+1)); echo "refused by both: $s"
      echo "   base: $(tail -1 "$out/base/$key.err")"; echo "   new:  $(tail -1 "$out/new/$key.err")"
    else
      diff=$((diff+1)); echo "DIFFERS (one refuses): $s"; tail -2 "$out"/*/"$key.err"
    fi
  elif cmp -s "$out/base/$key.exr" "$out/new/$key.exr"; then
    same=$((same+1))
  else
    diff=$((diff+1)); echo "DIFFERS: $s"
  fi
done
for s in $(find scenes -name '*.toml' | sort); do
  key=$(echo "$s" | tr '/' '_')
  "$base" convert "$s" -o "$out/base/$key.xml" >/dev/null 2>&1 || echo "(refuses to convert $s)" > "$out/base/$key.xml"
  "$new" convert "$s" -o "$out/new/$key.xml" >/dev/null 2>&1 || echo "(refuses to convert $s)" > "$out/new/$key.xml"
  cmp -s "$out/base/$key.xml" "$out/new/$key.xml" || echo "convert output differs: $s (diff $out/{base,new}/$key.xml)"
done
echo "images identical: $same, refused by both: $refused, differing: $diff"
[ $diff = 0 ]
