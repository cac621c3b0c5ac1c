// frames.js - what every engine's page hands `shadowbench score`, written once: from three readbacks of a frame
// (RGBA, rows bottom-up) lit by the sun with its shadows, lit without them, and drawn plain white on black, the
// visibility (the first over the second: N.L cancels; 0 where nothing is lit) and the mask (white where the engine
// drew geometry), each a PNG data URL with rows top-down.
function sbFramePngs(lit, open, mask, W, H) {
  const canvas = document.createElement("canvas");
  canvas.width = W, canvas.height = H;
  const ctx2d = canvas.getContext("2d");
  const png = (grey) => {
    const img = ctx2d.createImageData(W, H);
    for (let y = 0; y < H; y++)
      for (let x = 0; x < W; x++) {
        const v = grey[(H - 1 - y) * W + x], o = 4 * (y * W + x);
        img.data[o] = img.data[o + 1] = img.data[o + 2] = v;
        img.data[o + 3] = 255;
      }
    ctx2d.putImageData(img, 0, 0);
    return canvas.toDataURL("image/png");
  };
  const vis = new Uint8Array(W * H), m = new Uint8Array(W * H);
  for (let i = 0; i < W * H; i++) {
    const a = lit[4 * i], b = open[4 * i];
    vis[i] = b > 0 ? Math.min(255, Math.round((255 * a) / b)) : 0;
    m[i] = mask[4 * i] > 127 ? 255 : 0;
  }
  return { vis: png(vis), mask: png(m) };
}
