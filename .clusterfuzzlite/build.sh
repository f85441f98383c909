#!/bin/bash -eu
# Builds every fuzz target into $OUT with its seed corpus, dictionary and options, the same
# targets, seeds and settings fuzz/run uses. The image's cargo wrapper adds the sanitizer flags.
cd "$SRC/busspec/fuzz"
cargo fuzz build -O --debug-assertions
release=target/x86_64-unknown-linux-gnu/release
for t in $(./run list); do
  cp "$release/$t" "$OUT/"
  seeds=(corpus/"$t"/seed-*)
  if [ -d "regressions/$t" ]; then seeds+=(regressions/"$t"/*); fi
  if [ "$t" = spec_loader ]; then
    seeds+=(../spec/*.yaml ../model/tests/fixtures/valid/*.yaml ../model/tests/fixtures/broken/*.yaml)
  fi
  zip -q -j "$OUT/${t}_seed_corpus.zip" "${seeds[@]}"
  case $t in
    ub2_*) cp dict/ub2.dict "$OUT/$t.dict" ;;
    sd_*) cp dict/sd.dict "$OUT/$t.dict" ;;
  esac
  {
    echo "[libfuzzer]"
    echo "timeout = 10"
    case $t in *_stream) echo "max_len = 512" ;; esac
  } > "$OUT/$t.options"
done
