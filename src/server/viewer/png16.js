// A decoder for the 16-bit grayscale PNGs the server draws `depth` and `ids` pictures
// in. A browser would hand such an image to a canvas as 8 bits, losing the low byte
// (body values 1, 2, 3... all become 0), so the samples are read here: the IDAT stream is
// inflated with the browser's DecompressionStream and the row filters undone.

const SIGNATURE = [137, 80, 78, 71, 13, 10, 26, 10];

/**
 * A decoded 16-bit grayscale image, row-major from the top-left pixel.
 * @typedef {{width: number, height: number, data: Uint16Array}} Gray16
 */

/**
 * Inflates a zlib stream.
 * @param {Uint8Array} bytes
 * @returns {Promise<Uint8Array>}
 */
async function inflate(bytes) {
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
  return new Uint8Array(await new Response(stream).arrayBuffer());
}

/** The Paeth predictor of the PNG specification. */
function paeth(a, b, c) {
  const p = a + b - c;
  const pa = Math.abs(p - a);
  const pb = Math.abs(p - b);
  const pc = Math.abs(p - c);
  if (pa <= pb && pa <= pc) {
    return a;
  }
  return pb <= pc ? b : c;
}

/**
 * Decodes a non-interlaced 16-bit grayscale PNG.
 * @param {ArrayBuffer} buffer The file.
 * @returns {Promise<Gray16>}
 * @throws {Error} for anything else (another colour type or depth, interlacing, damage).
 */
export async function decodeGray16(buffer) {
  const bytes = new Uint8Array(buffer);
  const view = new DataView(buffer);
  if (bytes.length < 8 || SIGNATURE.some((b, i) => bytes[i] !== b)) {
    throw new Error("not a PNG file");
  }
  let width = 0;
  let height = 0;
  /** @type {Uint8Array[]} */
  const idat = [];
  let at = 8;
  while (at + 8 <= bytes.length) {
    const len = view.getUint32(at);
    const type = String.fromCharCode(...bytes.subarray(at + 4, at + 8));
    const body = bytes.subarray(at + 8, at + 8 + len);
    if (body.length !== len) {
      throw new Error(`PNG chunk ${type} is cut short`);
    }
    if (type === "IHDR") {
      width = view.getUint32(at + 8);
      height = view.getUint32(at + 12);
      const [depth, colour, , , interlace] = body.subarray(8, 13);
      if (depth !== 16 || colour !== 0 || interlace !== 0) {
        throw new Error(`expected a 16-bit grayscale PNG, got depth ${depth}, colour type ${colour}`);
      }
    } else if (type === "IDAT") {
      idat.push(body);
    } else if (type === "IEND") {
      break;
    }
    at += 12 + len;
  }
  if (!width || !height || idat.length === 0) {
    throw new Error("PNG without header or pixels");
  }
  const packed = new Uint8Array(idat.reduce((n, c) => n + c.length, 0));
  let o = 0;
  for (const c of idat) {
    packed.set(c, o);
    o += c.length;
  }
  const raw = await inflate(packed);
  const stride = width * 2;
  if (raw.length < height * (stride + 1)) {
    throw new Error("PNG pixel data is cut short");
  }
  const rows = new Uint8Array(height * stride);
  const bpp = 2;
  for (let y = 0; y < height; y++) {
    const filter = raw[y * (stride + 1)];
    const src = y * (stride + 1) + 1;
    const dst = y * stride;
    const up = dst - stride;
    for (let x = 0; x < stride; x++) {
      const a = x >= bpp ? rows[dst + x - bpp] : 0;
      const b = y > 0 ? rows[up + x] : 0;
      const c = y > 0 && x >= bpp ? rows[up + x - bpp] : 0;
      const r = raw[src + x];
      let value;
      switch (filter) {
        case 0:
          value = r;
          break;
        case 1:
          value = r + a;
          break;
        case 2:
          value = r + b;
          break;
        case 3:
          value = r + ((a + b) >> 1);
          break;
        case 4:
          value = r + paeth(a, b, c);
          break;
        default:
          throw new Error(`PNG row ${y} has unknown filter ${filter}`);
      }
      rows[dst + x] = value & 0xff;
    }
  }
  const data = new Uint16Array(width * height);
  for (let i = 0; i < data.length; i++) {
    data[i] = (rows[2 * i] << 8) | rows[2 * i + 1];
  }
  return { width, height, data };
}
