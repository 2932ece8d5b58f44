// Compares two PNGs (8-bit RGB or RGBA, as chromium's screenshots and prt render's PNGs are) over
// the first WIDTH x HEIGHT pixels of each: relative L2 of the tone-mapped values (||A - B|| / ||B||,
// every channel in [0, 1]) and the worst BLOCK x BLOCK block's mean absolute difference. Node's own
// zlib only: no npm packages. Prints one JSON line.
// Usage: node web_compare.js A.png B.png WIDTH HEIGHT [BLOCK [SIDE.png]]; SIDE.png: A, B and
// 8 |A - B| side by side, to look at.
'use strict';
const fs = require('fs'), zlib = require('zlib');

function decode(path) {
    const buf = fs.readFileSync(path);
    if (buf.readUInt32BE(0) !== 0x89504e47) throw new Error(path + ': not a PNG');
    let at = 8, width = 0, height = 0, type = 0, depth = 0, interlace = 0;
    const idat = [];
    while (at < buf.length) {
        const len = buf.readUInt32BE(at), kind = buf.toString('latin1', at + 4, at + 8), data = buf.subarray(at + 8, at + 8 + len);
        if (kind === 'IHDR') { width = data.readUInt32BE(0); height = data.readUInt32BE(4); depth = data[8]; type = data[9]; interlace = data[12]; }
        else if (kind === 'IDAT') idat.push(data);
        else if (kind === 'IEND') break;
        at += 12 + len;
    }
    const channels = {2: 3, 6: 4}[type];
    if (depth !== 8 || !channels || interlace) throw new Error(path + ': only 8-bit RGB or RGBA, not interlaced');
    const raw = zlib.inflateSync(Buffer.concat(idat)), stride = width * channels, px = Buffer.alloc(height * stride);
    for (let y = 0; y < height; ++y) {
        const filter = raw[y * (stride + 1)], line = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
        for (let x = 0; x < stride; ++x) {
            const a = x >= channels ? px[y * stride + x - channels] : 0, b = y ? px[(y - 1) * stride + x] : 0;
            const c = x >= channels && y ? px[(y - 1) * stride + x - channels] : 0;
            let v = line[x];
            if (filter === 1) v += a;
            else if (filter === 2) v += b;
            else if (filter === 3) v += (a + b) >> 1;
            else if (filter === 4) { const p = a + b - c, pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c); v += pa <= pb && pa <= pc ? a : pb <= pc ? b : c; }
            px[y * stride + x] = v & 255;
        }
    }
    return {width, height, channels, px};
}

function encode(path, width, height, rgb) {
    const raw = Buffer.alloc(height * (width * 3 + 1));
    for (let y = 0; y < height; ++y) rgb.copy(raw, y * (width * 3 + 1) + 1, y * width * 3, (y + 1) * width * 3);
    const chunk = (kind, data) => {
        const head = Buffer.alloc(8), crc = Buffer.alloc(4);
        head.writeUInt32BE(data.length, 0);
        head.write(kind, 4, 'latin1');
        crc.writeUInt32BE(zlib.crc32(Buffer.concat([head.subarray(4), data])) >>> 0, 0);
        return Buffer.concat([head, data, crc]);
    };
    const ihdr = Buffer.alloc(13);
    ihdr.writeUInt32BE(width, 0);
    ihdr.writeUInt32BE(height, 4);
    ihdr[8] = 8;
    ihdr[9] = 2;
    fs.writeFileSync(path, Buffer.concat([Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]), chunk('IHDR', ihdr),
                                          chunk('IDAT', zlib.deflateSync(raw)), chunk('IEND', Buffer.alloc(0))]));
}

const [A, B, W, H, BL, SIDE] = process.argv.slice(2);
const a = decode(A), b = decode(B), w = +W, h = +H, block = +(BL || 16);
if (a.width < w || a.height < h || b.width < w || b.height < h) throw new Error(`images smaller than ${w}x${h}: ${a.width}x${a.height}, ${b.width}x${b.height}`);
let se = 0, sb = 0, worst = 0, worstAt = [0, 0];
for (let by = 0; by < h; by += block)
    for (let bx = 0; bx < w; bx += block) {
        let sum = 0, count = 0;
        for (let y = by; y < Math.min(h, by + block); ++y)
            for (let x = bx; x < Math.min(w, bx + block); ++x)
                for (let c = 0; c < 3; ++c) {
                    const va = a.px[(y * a.width + x) * a.channels + c] / 255, vb = b.px[(y * b.width + x) * b.channels + c] / 255;
                    se += (va - vb) * (va - vb);
                    sb += vb * vb;
                    sum += Math.abs(va - vb);
                    count++;
                }
        if (sum / count > worst) { worst = sum / count; worstAt = [bx, by]; }
    }
if (SIDE) {
    const out = Buffer.alloc(3 * w * h * 3);
    for (let y = 0; y < h; ++y)
        for (let x = 0; x < w; ++x)
            for (let c = 0; c < 3; ++c) {
                const va = a.px[(y * a.width + x) * a.channels + c], vb = b.px[(y * b.width + x) * b.channels + c];
                out[(y * 3 * w + x) * 3 + c] = va;
                out[(y * 3 * w + w + x) * 3 + c] = vb;
                out[(y * 3 * w + 2 * w + x) * 3 + c] = Math.min(255, 8 * Math.abs(va - vb));
            }
    encode(SIDE, 3 * w, h, out);
}
console.log(JSON.stringify({relative_l2: Math.sqrt(se / sb), worst_block: worst, worst_block_at: worstAt, block}));
