// Encodes one raw RGBA8 image (top row first) as a KTX2 file with Basis
// Universal (npm ktx2-encoder, the Basis Universal encoder compiled to
// WebAssembly; pinned in tools/package-lock.json), with a full mip chain.
// Called by the export.gltf stage (stages/export/ktx2_encode.cc).
//
// Two encoders: ktx2-encoder 0.6.0 (Basis Universal 2.5's WebAssembly), whose
// limit is 12 Mpix (it refuses a 4096² map), and ktx2-encoder 0.5.4 (the
// previous generation's WebAssembly, installed as ktx2-encoder-legacy), which
// encodes 4096² maps (docs/export.md, "Maps above 12 Mpix"). The caller
// chooses (stages/export/ktx2_encode.cc, by the image's size). The same
// options; each is deterministic.
//
// Usage: node encode_ktx2.mjs etc1s|uastc srgb|linear WIDTH HEIGHT IN.rgba OUT.ktx2 [PACKAGE]
//   PACKAGE: ktx2-encoder (the default) or ktx2-encoder-legacy
//   etc1s: BasisLZ/ETC1S, quality level 255, effort 1 (for color maps)
//   uastc: UASTC 4x4, effort 0, Zstandard supercompression and the
//          encoder's normal-map tuning (for normal maps)
//   srgb / linear: the data's transfer function (color maps are sRGB,
//          normal maps linear)
// Exit status 0 on success; 2 on bad arguments; 1 when encoding fails, with
// the reason on stderr.
import { readFileSync, writeFileSync, renameSync } from "node:fs";

const [codec, transfer, widthText, heightText, input, output, pkg = "ktx2-encoder"] =
  process.argv.slice(2);
const width = Number(widthText), height = Number(heightText);
if (!["etc1s", "uastc"].includes(codec) || !["srgb", "linear"].includes(transfer) ||
    !(width > 0) || !(height > 0) || !input || !output ||
    !["ktx2-encoder", "ktx2-encoder-legacy"].includes(pkg)) {
  console.error("usage: node encode_ktx2.mjs etc1s|uastc srgb|linear WIDTH HEIGHT IN.rgba OUT.ktx2 " +
                "[ktx2-encoder|ktx2-encoder-legacy]");
  process.exit(2);
}
const rgba = readFileSync(input);
if (rgba.length !== width * height * 4) {
  console.error(`${input}: ${rgba.length} bytes, expected ${width}x${height}x4 = ${width * height * 4}`);
  process.exit(2);
}
const { encodeToKTX2 } = await import(pkg);
const srgb = transfer === "srgb";
const options = {
  isUASTC: codec === "uastc",
  isKTX2File: true,
  generateMipmap: true,
  isPerceptual: srgb,
  isSetKTX2SRGBTransferFunc: srgb,
  imageDecoder: async () => ({ width, height, data: new Uint8Array(rgba.buffer, rgba.byteOffset, rgba.length) }),
};
if (codec === "etc1s") {
  options.qualityLevel = 255;  // the most endpoint/selector clusters: the least blur
  options.compressionLevel = 1;  // effort 1 of 0-6: 25 % faster than the default 2, same size
} else {
  options.isNormalMap = true;
  options.needSupercompression = true;
  options.uastcLDRQualityLevel = 0;  // effort "fastest": 2.6x faster than the default on 2048²
}
try {
  const ktx2 = await encodeToKTX2(new Uint8Array(0), options);
  writeFileSync(output + ".tmp", ktx2);
  renameSync(output + ".tmp", output);
} catch (error) {
  // Above 4096² the older encoder may run out of its WebAssembly heap and
  // abort without a reason (an 8192² ETC1S color map does; UASTC encodes).
  const hint = pkg === "ktx2-encoder-legacy" && width * height > 4096 * 4096
    ? " (a map above 4096² can exhaust the WebAssembly encoder's heap: an 8192² color map " +
      "does; bake the maps at 4096² or less for KTX2)"
    : "";
  console.error(`encoding ${input} (${width}x${height}, ${codec}, ${pkg}): ${error.message ?? error}${hint}`);
  process.exit(1);
}
