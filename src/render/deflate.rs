//! The DEFLATE encoder behind the renderer's PNG files (RFC 1950 zlib around RFC 1951
//! DEFLATE), built for speed on rendered pictures.
//!
//! - **Bands**: the rows are cut into bands, about four per rayon thread and none under
//!   64 KiB of filtered data (a small image is one band), compressed in parallel as pigz
//!   does. Each band is raw DEFLATE ending in a sync flush (an empty stored block), so it
//!   is byte-aligned and refers to nothing before it, and the bands concatenate into one
//!   stream.
//! - **Compression**: within a band, dynamic-Huffman blocks of at most 65,536 symbols,
//!   each with codes built from its own symbol counts; the only matches are runs of zero
//!   bytes (copies at distance 1), which is what Up-filtered flat areas become. There is
//!   no general match search, which is where the speed comes from; on rendered pictures
//!   the files are still smaller than the `png` crate's `Fast` setting makes, and noise
//!   costs about one byte per byte.
//! - **Stream**: a two-byte zlib header (32 KiB window, "fastest" level), the bands in
//!   order, a final empty stored block, and the Adler-32 of all filtered bytes, combined
//!   from the bands' own checksums.
//!
//! No crate offers this at this speed. `fdeflate` (the `png` crate's encoder) cannot end
//! a stream with a flush, so its outputs cannot be joined; `miniz_oxide` with a sync
//! flush takes more than twice the time; zlib-rs (the Rust port of zlib-ng) at level 1
//! with its run-length strategy (`Z_RLE`), compressing the same bands in parallel, took
//! 2.2× the time on the 1280 × 960 shaded picture and 2.0× on the 16-bit depth image
//! (2.09 against 0.94 ms, 0.94 against 0.48 ms; `cargo bench --bench png`, the
//! `*_zlib_rs_rle` cases, 2026-11-27, recorded in BENCHMARKS.md). Its files are 0.3 % and
//! 4.8 % smaller, since it also matches runs of bytes other than zero.

use std::ops::Range;

use rayon::prelude::*;

/// PNG filter type 2, "Up": each byte minus the byte above it.
const FILTER_UP: u8 = 2;
/// Filtered bytes a band holds at least, unless the image is smaller.
const MIN_BAND_BYTES: usize = 64 << 10;
/// Bands per rayon thread, so that uneven bands still keep every thread busy.
const BANDS_PER_THREAD: usize = 4;
/// Symbols after which a band starts a new DEFLATE block (and new Huffman codes).
const BLOCK_SYMBOLS: usize = 1 << 16;
/// Zero runs shorter than this are written as literal bytes rather than a match.
const MIN_RUN: usize = 5;
/// zlib header: DEFLATE with a 32 KiB window, level "fastest", no dictionary (a multiple of 31).
pub(super) const ZLIB_HEADER: [u8; 2] = [0x78, 0x01];
/// A final empty stored block: BFINAL = 1, BTYPE = 00, LEN = 0, NLEN = !0.
const FINAL_EMPTY_BLOCK: [u8; 5] = [0x01, 0x00, 0x00, 0xff, 0xff];
/// Rows per band for an image of `rows` lines of `line` filtered bytes: about
/// [`BANDS_PER_THREAD`] bands per rayon thread, none under [`MIN_BAND_BYTES`].
pub(super) fn band_rows(rows: usize, line: usize) -> usize {
    let bands = rayon::current_num_threads().max(1) * BANDS_PER_THREAD;
    rows.div_ceil(bands)
        .max(MIN_BAND_BYTES.div_ceil(line))
        .max(1)
}

/// The zlib stream of the Up-filtered image (each line a filter-type byte and the row),
/// its bands of `band_rows` rows compressed in parallel.
pub(super) fn zlib_stream(
    rows: usize,
    row_bytes: usize,
    band_rows: usize,
    filter_up: &(impl Fn(usize, &mut [u8]) + Sync),
) -> Vec<u8> {
    let bands: Vec<Band> = (0..rows.div_ceil(band_rows))
        .into_par_iter()
        .map(|b| {
            let band = b * band_rows..((b + 1) * band_rows).min(rows);
            deflate_band(band, row_bytes, filter_up)
        })
        .collect();
    frame(&bands)
}

/// The zlib stream [`zlib_stream`] makes, cut into the same bands, but with each band's
/// Up-filtered bytes (filter-type bytes included) compressed by `compress`, which must
/// return raw DEFLATE ending in a sync flush. It measures other DEFLATE encoders on
/// exactly the input and framing of this one.
pub(super) fn zlib_stream_with(
    rows: usize,
    row_bytes: usize,
    band_rows: usize,
    filter_up: &(impl Fn(usize, &mut [u8]) + Sync),
    compress: &(impl Fn(&[u8]) -> Vec<u8> + Sync),
) -> Vec<u8> {
    let bands: Vec<Band> = (0..rows.div_ceil(band_rows))
        .into_par_iter()
        .map(|b| {
            let band = b * band_rows..((b + 1) * band_rows).min(rows);
            let mut filtered = vec![0; band.len() * (row_bytes + 1)];
            for (y, line) in band.zip(filtered.chunks_exact_mut(row_bytes + 1)) {
                line[0] = FILTER_UP;
                filter_up(y, &mut line[1..]);
            }
            Band {
                deflate: compress(&filtered),
                adler: simd_adler32::adler32(&filtered.as_slice()),
                len: filtered.len(),
            }
        })
        .collect();
    frame(&bands)
}

/// The zlib stream around `bands`: header, the bands in order, a final empty stored
/// block and the combined Adler-32.
fn frame(bands: &[Band]) -> Vec<u8> {
    let size: usize = bands.iter().map(|b| b.deflate.len()).sum();
    let mut z = Vec::with_capacity(ZLIB_HEADER.len() + size + FINAL_EMPTY_BLOCK.len() + 4);
    z.extend_from_slice(&ZLIB_HEADER);
    let mut adler = 1;
    for band in bands {
        z.extend_from_slice(&band.deflate);
        adler = adler32_combine(adler, band.adler, band.len);
    }
    z.extend_from_slice(&FINAL_EMPTY_BLOCK);
    z.extend_from_slice(&adler.to_be_bytes());
    z
}

/// One band, compressed.
struct Band {
    /// Raw DEFLATE: non-final blocks ending in a sync flush.
    deflate: Vec<u8>,
    /// Adler-32 of the band's filtered bytes.
    adler: u32,
    /// Number of filtered bytes.
    len: usize,
}

/// Filters and compresses the image rows `rows`.
fn deflate_band(
    rows: Range<usize>,
    row_bytes: usize,
    filter_up: &impl Fn(usize, &mut [u8]),
) -> Band {
    let len = rows.len() * (row_bytes + 1);
    let mut line = vec![0; row_bytes + 1];
    line[0] = FILTER_UP;
    let mut adler = simd_adler32::Adler32::new();
    let mut symbols = Symbols::new();
    let mut bits = Bits::with_capacity(len / 8);
    for y in rows {
        filter_up(y, &mut line[1..]);
        adler.write(&line);
        symbols.push_line(&line);
        if symbols.len + symbols.copies.len() >= BLOCK_SYMBOLS {
            write_block(&mut bits, &symbols);
            symbols.clear();
        }
    }
    symbols.end_run();
    if symbols.len > 0 {
        write_block(&mut bits, &symbols);
    }
    bits.sync_flush();
    Band {
        deflate: bits.out,
        adler: adler.finish(),
        len,
    }
}

/// The Adler-32 of `a`'s bytes followed by `len_b` bytes whose Adler-32 is `b` (zlib's
/// `adler32_combine`).
fn adler32_combine(a: u32, b: u32, len_b: usize) -> u32 {
    const MOD: u64 = 65521;
    let n = len_b as u64 % MOD;
    let (a1, a2) = (a as u64 & 0xffff, a as u64 >> 16);
    let (b1, b2) = (b as u64 & 0xffff, b as u64 >> 16);
    // Appending bytes to `a` adds b1 - 1 to the sum and n·a1 + b2 - n to the sum of sums.
    let s1 = (a1 + b1 + MOD - 1) % MOD;
    let s2 = (a2 + b2 + n * a1 + MOD - n) % MOD;
    (s2 << 16 | s1) as u32
}

/// A block's symbols: literal bytes, and copies from distance 1 (which repeat a zero
/// literal) between them.
struct Symbols {
    /// The literal bytes, `len` of them; the rest is room (zeroed only as first needed).
    literals: Vec<u8>,
    len: usize,
    /// Copies as (literals before the copy, bytes copied: 4 or more).
    copies: Vec<(usize, usize)>,
    /// Zero bytes seen and not yet written as symbols.
    run: usize,
}

impl Symbols {
    fn new() -> Symbols {
        Symbols {
            literals: Vec::new(),
            len: 0,
            copies: Vec::new(),
            run: 0,
        }
    }

    /// Forgets the block's symbols, keeping the pending zero run for the next block.
    fn clear(&mut self) {
        self.len = 0;
        self.copies.clear();
    }

    /// Writes the pending zero run as symbols.
    fn end_run(&mut self) {
        if self.run > 0 {
            if self.literals.len() < self.len + 8 {
                self.literals.resize(self.len + 8, 0);
            }
            self.len = push_run(&mut self.literals, &mut self.copies, self.len, self.run);
            self.run = 0;
        }
    }

    /// Appends one filtered line. Its first byte (the filter type) is not zero, so zero
    /// runs never cross lines.
    fn push_line(&mut self, line: &[u8]) {
        // A line adds at most one literal per byte, plus 8 bytes that may be stored past
        // the end.
        let room = self.len + line.len() + 8;
        if self.literals.len() < room {
            self.literals.resize(room.max(2 * self.literals.len()), 0);
        }
        // Locals rather than fields, so that the stores do not reload them.
        let (lits, copies) = (&mut self.literals[..], &mut self.copies);
        let (mut n, mut run) = (self.len, self.run);
        let mut wide = line.chunks_exact(32);
        for c in &mut wide {
            // Skip 32 zero bytes at a time: most of a rendered picture.
            let (lo, hi) = c.split_at(16);
            let any = u128::from_le_bytes(lo.try_into().expect("16 bytes"))
                | u128::from_le_bytes(hi.try_into().expect("16 bytes"));
            if any == 0 {
                run += 32;
                continue;
            }
            for w in c.chunks_exact(8) {
                push_word(lits, copies, &mut n, &mut run, w);
            }
        }
        let mut words = wide.remainder().chunks_exact(8);
        for w in &mut words {
            push_word(lits, copies, &mut n, &mut run, w);
        }
        for &b in words.remainder() {
            if b == 0 {
                run += 1;
            } else {
                if run > 0 {
                    n = push_run(lits, copies, n, run);
                    run = 0;
                }
                lits[n] = b;
                n += 1;
            }
        }
        self.len = n;
        self.run = run;
    }
}

/// Appends the symbols of 8 bytes `w`: its leading zero bytes extend the pending run, its
/// trailing ones start the next, and the bytes between are literals (zeros included).
#[inline(always)]
fn push_word(
    lits: &mut [u8],
    copies: &mut Vec<(usize, usize)>,
    n: &mut usize,
    run: &mut usize,
    w: &[u8],
) {
    let word = u64::from_le_bytes(w.try_into().expect("8 bytes"));
    if word == 0 {
        *run += 8;
        return;
    }
    let lead = (word.trailing_zeros() / 8) as usize;
    let tail = (word.leading_zeros() / 8) as usize;
    *run += lead;
    if *run > 0 {
        *n = push_run(lits, copies, *n, *run);
    }
    // One 8-byte store, of which the literals count.
    lits[*n..*n + 8].copy_from_slice(&(word >> (8 * lead)).to_le_bytes());
    *n += 8 - lead - tail;
    *run = tail;
}

/// Appends the symbols of `run` (> 0) zero bytes after literal `n`: short runs as
/// literals (stored as 8 zeros, so `lits` needs room for 8), longer ones as a literal zero
/// and a copy of it; returns the new literal count.
#[inline(never)]
fn push_run(lits: &mut [u8], copies: &mut Vec<(usize, usize)>, n: usize, run: usize) -> usize {
    if run < MIN_RUN {
        lits[n..n + 8].fill(0);
        return n + run;
    }
    lits[n] = 0;
    copies.push((n + 1, run - 1));
    n + 1
}

/// The lengths (3 to 258) of the copies that repeat `len` (at least 3) bytes.
fn copy_lengths(len: usize) -> impl Iterator<Item = usize> {
    let mut rest = len;
    std::iter::from_fn(move || {
        // Take 258 at a time, but never leave 1 or 2 bytes over.
        let take = match rest {
            0 => return None,
            259 | 260 => rest - 3,
            _ => rest.min(258),
        };
        rest -= take;
        Some(take)
    })
}

/// Little-endian bit output, as DEFLATE packs its bits.
struct Bits {
    out: Vec<u8>,
    /// Pending bits, fewer than 8 between calls.
    acc: u64,
    nbits: u32,
}

impl Bits {
    fn with_capacity(bytes: usize) -> Bits {
        Bits {
            out: Vec::with_capacity(bytes),
            acc: 0,
            nbits: 0,
        }
    }

    /// Writes the `n` (at most 32) low bits of `bits`.
    fn put(&mut self, bits: u32, n: u32) {
        self.acc |= (bits as u64) << self.nbits;
        self.nbits += n;
        while self.nbits >= 8 {
            self.out.push(self.acc as u8);
            self.acc >>= 8;
            self.nbits -= 8;
        }
    }

    /// Writes the block body `symbols` with the codes of `literal` and `copy` (per byte
    /// value and per copy length: code | bit count << 24), `total` bits in all.
    fn put_symbols(
        &mut self,
        symbols: &Symbols,
        literal: &[u32; 256],
        copy: &[u32; 259],
        total: usize,
    ) {
        let start = self.out.len();
        self.out.resize(start + total / 8 + 16, 0);
        let mut w = FastBits {
            out: &mut self.out[start..],
            pos: 0,
            acc: self.acc,
            nbits: self.nbits,
        };
        let mut from = 0;
        for &(at, len) in &symbols.copies {
            w.literals(&symbols.literals[from..at], literal);
            for l in copy_lengths(len) {
                w.add(copy[l]);
                w.store();
            }
            from = at;
        }
        w.literals(&symbols.literals[from..symbols.len], literal);
        let (pos, acc, nbits) = (w.pos, w.acc, w.nbits);
        self.out.truncate(start + pos);
        (self.acc, self.nbits) = (acc, nbits);
    }

    /// Ends the stream so far with an empty stored block (BFINAL = 0, BTYPE = 00), which
    /// pads to a byte boundary: zlib's sync flush.
    fn sync_flush(&mut self) {
        self.put(0, 3);
        if self.nbits > 0 {
            self.put(0, 8 - self.nbits);
        }
        self.out.extend_from_slice(&[0x00, 0x00, 0xff, 0xff]);
    }
}

/// The hot loop of [`Bits`]: codes go into room sized beforehand, one 8-byte store per
/// up to three literal codes (at most 15 bits each: with fewer than 8 pending bits, 52 in
/// all) or per copy code (at most 15 + 5 extra + 1 distance bits).
struct FastBits<'a> {
    out: &'a mut [u8],
    pos: usize,
    acc: u64,
    nbits: u32,
}

impl FastBits<'_> {
    /// Adds a code: `entry` is its bits | their number << 24.
    #[inline(always)]
    fn add(&mut self, entry: u32) {
        self.acc |= ((entry & 0xff_ffff) as u64) << self.nbits;
        self.nbits += entry >> 24;
    }

    /// Stores the pending bits and keeps the fewer than 8 of an incomplete byte.
    #[inline(always)]
    fn store(&mut self) {
        self.out[self.pos..self.pos + 8].copy_from_slice(&self.acc.to_le_bytes());
        let bytes = self.nbits / 8;
        self.pos += bytes as usize;
        self.acc >>= bytes * 8;
        self.nbits -= bytes * 8;
    }

    #[inline(always)]
    fn literals(&mut self, bytes: &[u8], literal: &[u32; 256]) {
        let mut threes = bytes.chunks_exact(3);
        for t in &mut threes {
            self.add(literal[t[0] as usize]);
            self.add(literal[t[1] as usize]);
            self.add(literal[t[2] as usize]);
            self.store();
        }
        for &b in threes.remainder() {
            self.add(literal[b as usize]);
            self.store();
        }
    }
}

/// Lengths 3..=258 of a copy: (symbol, extra bits, base length), RFC 1951 §3.2.5.
const LENGTH_CODES: [(u16, u8, u16); 259] = {
    const EXTRA: [u8; 28] = [
        0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5,
    ];
    let mut t = [(0, 0, 0); 259];
    let (mut s, mut base) = (0, 3);
    while s < 28 {
        let mut k = 0;
        while k < 1 << EXTRA[s] && base + k < 259 {
            t[(base + k) as usize] = (257 + s as u16, EXTRA[s], base);
            k += 1;
        }
        base += 1 << EXTRA[s];
        s += 1;
    }
    // 258 has its own symbol (284 with 31 extra would be 258 too, but is not allowed).
    t[258] = (285, 0, 258);
    t
};

/// The order in which a dynamic block lists the code-length code's lengths.
const CODE_LENGTH_ORDER: [usize; 19] = [
    16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15,
];

/// Writes `symbols` as one non-final dynamic-Huffman block. Its distance code has two
/// 1-bit codes (a complete code); only the first, distance 1, is used.
fn write_block(bits: &mut Bits, symbols: &Symbols) {
    // Literal counts, in four tables so that repeated bytes do not wait on each other.
    let literals = &symbols.literals[..symbols.len];
    let mut tables = [[0u32; 256]; 4];
    let mut quads = literals.chunks_exact(4);
    for q in &mut quads {
        for (t, &b) in tables.iter_mut().zip(q) {
            t[b as usize] += 1;
        }
    }
    for &b in quads.remainder() {
        tables[0][b as usize] += 1;
    }
    let mut counts = [0u32; 286];
    for (b, c) in counts.iter_mut().take(256).enumerate() {
        *c = tables.iter().map(|t| t[b]).sum();
    }
    let mut copy_counts = [0u32; 259];
    for &(_, len) in &symbols.copies {
        for l in copy_lengths(len) {
            copy_counts[l] += 1;
        }
    }
    for (l, &c) in copy_counts.iter().enumerate().skip(3) {
        counts[LENGTH_CODES[l].0 as usize] += c;
    }
    counts[256] = 1; // end of block

    let lengths = code_lengths(&counts, 15);
    let codes = canonical_codes(&lengths);
    // Codes as `code | bit count << 24`: literals, and copies with their extra bits and
    // the 1-bit distance code 0.
    let mut literal = [0u32; 256];
    let mut total = 0;
    for (b, entry) in literal.iter_mut().enumerate() {
        *entry = codes[b] | (lengths[b] as u32) << 24;
        total += counts[b] as usize * lengths[b] as usize;
    }
    let mut copy = [0u32; 259];
    for (l, entry) in copy.iter_mut().enumerate().skip(3) {
        let (sym, extra, base) = LENGTH_CODES[l];
        let n = lengths[sym as usize] as u32;
        let bits = n + extra as u32 + 1;
        *entry = codes[sym as usize] | (l as u32 - base as u32) << n | bits << 24;
        total += copy_counts[l] as usize * bits as usize;
    }

    // The header: the literal/length code lengths, then the two distance code lengths,
    // run-length coded with the code-length code.
    let hlit = (257..286)
        .rev()
        .find(|&s| lengths[s] > 0)
        .map_or(257, |s| s + 1);
    let mut all = lengths[..hlit].to_vec();
    all.extend_from_slice(&[1, 1]);
    let runs = run_length_code(&all);
    let mut cl_counts = [0u32; 19];
    for &(s, _) in &runs {
        cl_counts[s as usize] += 1;
    }
    let cl_lengths = code_lengths(&cl_counts, 7);
    let cl_codes = canonical_codes(&cl_lengths);
    let hclen = (4..=19)
        .rev()
        .find(|&k| cl_lengths[CODE_LENGTH_ORDER[k - 1]] > 0)
        .unwrap_or(4);

    bits.put(2 << 1, 3); // BFINAL = 0, BTYPE = 2 (dynamic Huffman)
    bits.put((hlit - 257) as u32, 5);
    bits.put(1, 5); // HDIST = 1: two distance codes
    bits.put((hclen - 4) as u32, 4);
    for &s in &CODE_LENGTH_ORDER[..hclen] {
        bits.put(cl_lengths[s] as u32, 3);
    }
    for &(s, extra) in &runs {
        let s = s as usize;
        bits.put(cl_codes[s], cl_lengths[s] as u32);
        match s {
            16 => bits.put(extra as u32, 2),
            17 => bits.put(extra as u32, 3),
            18 => bits.put(extra as u32, 7),
            _ => {}
        }
    }
    bits.put_symbols(symbols, &literal, &copy, total);
    bits.put(codes[256], lengths[256] as u32);
}

/// Code lengths as a dynamic block's header codes them (RFC 1951 §3.2.7): pairs of a
/// code-length symbol and its extra bits (16: repeat the previous length 3 to 6 times;
/// 17 and 18: 3 to 10 and 11 to 138 zeros).
fn run_length_code(lengths: &[u8]) -> Vec<(u8, u8)> {
    let mut out = Vec::with_capacity(lengths.len());
    let mut i = 0;
    while i < lengths.len() {
        let l = lengths[i];
        let same = lengths[i..].iter().take_while(|&&x| x == l).count();
        if l == 0 && same >= 3 {
            let n = same.min(138);
            out.push(if n >= 11 {
                (18, (n - 11) as u8)
            } else {
                (17, (n - 3) as u8)
            });
            i += n;
        } else if l != 0 && same >= 4 {
            let n = (same - 1).min(6);
            out.push((l, 0));
            out.push((16, (n - 3) as u8));
            i += 1 + n;
        } else {
            out.push((l, 0));
            i += 1;
        }
    }
    out
}

/// Huffman code lengths for symbol `counts` (0 for a symbol that does not occur), none
/// longer than `limit`. At least two symbols get a code, so the code is complete (the
/// lengths' Kraft sum is exactly 1), as strict decoders require.
fn code_lengths(counts: &[u32], limit: usize) -> Vec<u8> {
    // Leaves as count << 16 | symbol, sorted by count.
    let mut leaves: Vec<u64> = (counts.iter().enumerate())
        .filter(|&(_, &c)| c > 0)
        .map(|(s, &c)| (c as u64) << 16 | s as u64)
        .collect();
    // Fewer than two: add unused symbols with a count of zero.
    let unused = (0..counts.len() as u64).filter(|&s| counts[s as usize] == 0);
    leaves.extend(unused.take(2usize.saturating_sub(leaves.len())));
    leaves.sort_unstable();
    let n = leaves.len();

    // Huffman's tree with two queues: the sorted leaves, and the internal nodes in the
    // order made (which is also sorted). Node k < n is leaf k; the root is 2n - 2.
    let mut weight: Vec<u64> = leaves.iter().map(|&l| l >> 16).collect();
    let mut parent = vec![0; 2 * n - 1];
    let (mut leaf, mut node) = (0, n);
    for k in n..2 * n - 1 {
        let mut pair = [0; 2];
        for p in &mut pair {
            if leaf < n && (node == k || weight[leaf] <= weight[node]) {
                *p = leaf;
                leaf += 1;
            } else {
                *p = node;
                node += 1;
            }
        }
        weight.push(weight[pair[0]] + weight[pair[1]]);
        parent[pair[0]] = k;
        parent[pair[1]] = k;
    }
    let mut depth = vec![0usize; 2 * n - 1];
    let mut per_length = [0usize; 64];
    for k in (0..2 * n - 2).rev() {
        depth[k] = depth[parent[k]] + 1;
        if k < n {
            per_length[depth[k]] += 1;
        }
    }

    // Limit the lengths as miniz does: make every longer code `limit` long, then, while
    // the Kraft sum is over 1, move one code from `limit` down to the next shorter length
    // in use, splitting it into two.
    for l in limit + 1..64 {
        per_length[limit] += per_length[l];
        per_length[l] = 0;
    }
    let mut kraft: usize = (1..=limit).map(|l| per_length[l] << (limit - l)).sum();
    while kraft > 1 << limit {
        per_length[limit] -= 1;
        if let Some(l) = (1..limit).rev().find(|&l| per_length[l] > 0) {
            per_length[l] -= 1;
            per_length[l + 1] += 2;
        }
        kraft -= 1;
    }

    // The longest codes go to the rarest symbols.
    let mut lengths = vec![0; counts.len()];
    let mut rarest_first = leaves.iter();
    for l in (1..=limit).rev() {
        for &leaf in rarest_first.by_ref().take(per_length[l]) {
            lengths[(leaf & 0xffff) as usize] = l as u8;
        }
    }
    lengths
}

/// The canonical Huffman codes of `lengths` (RFC 1951 §3.2.2), bit-reversed for
/// [`Bits`], which writes the least significant bit first.
fn canonical_codes(lengths: &[u8]) -> Vec<u32> {
    let mut per_length = [0u32; 16];
    for &l in lengths {
        per_length[l as usize] += 1;
    }
    per_length[0] = 0;
    let mut next = [0u32; 16];
    let mut code = 0;
    for l in 1..16 {
        code = (code + per_length[l - 1]) << 1;
        next[l] = code;
    }
    lengths
        .iter()
        .map(|&l| {
            if l == 0 {
                return 0;
            }
            let c = next[l as usize];
            next[l as usize] += 1;
            c.reverse_bits() >> (32 - l as u32)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sample::SplitMix64;

    #[test]
    fn an_empty_band_list_is_still_a_zlib_stream() {
        let z = zlib_stream(0, 12, 4, &|_, _: &mut [u8]| unreachable!());
        assert_eq!(
            miniz_oxide::inflate::decompress_to_vec_zlib(&z).unwrap(),
            Vec::<u8>::new()
        );
    }

    #[test]
    fn huffman_codes_are_complete_and_within_the_limit() {
        let kraft = |lengths: &[u8]| -> f64 {
            lengths
                .iter()
                .filter(|&&l| l > 0)
                .map(|&l| 0.5f64.powi(l as i32))
                .sum()
        };
        // Fibonacci counts make a 30-deep tree: the limit must cut it.
        let mut fib = vec![1u32, 1];
        while fib.len() < 30 {
            fib.push(fib[fib.len() - 1] + fib[fib.len() - 2]);
        }
        for limit in [7, 9, 15] {
            let lengths = code_lengths(&fib, limit);
            assert!(
                lengths.iter().all(|&l| (1..=limit as u8).contains(&l)),
                "{lengths:?}"
            );
            assert_eq!(kraft(&lengths), 1.0, "{lengths:?}");
            // Rarer symbols never get shorter codes.
            assert!(lengths.windows(2).all(|p| p[0] >= p[1]), "{lengths:?}");
        }
        // Within the limit, Huffman's own lengths.
        assert_eq!(code_lengths(&[1, 1, 2, 4, 0], 15), [3, 3, 2, 1, 0]);
        // One symbol, or none, still makes a complete two-symbol code.
        let one = code_lengths(&[0, 0, 5, 0], 15);
        assert_eq!(one[2], 1);
        assert_eq!(kraft(&one), 1.0);
        assert_eq!(kraft(&code_lengths(&[0; 19], 7)), 1.0);
        // Canonical codes: RFC 1951's example (lengths 3,3,3,3,3,2,4,4), bit-reversed.
        let codes = canonical_codes(&[3, 3, 3, 3, 3, 2, 4, 4]);
        let msb_first = [0b010, 0b011, 0b100, 0b101, 0b110, 0b00, 0b1110, 0b1111];
        for ((&c, &m), l) in codes.iter().zip(&msb_first).zip([3, 3, 3, 3, 3, 2, 4, 4]) {
            assert_eq!(c, (m as u32).reverse_bits() >> (32 - l));
        }
    }

    #[test]
    fn length_codes_follow_rfc_1951() {
        assert_eq!(LENGTH_CODES[3], (257, 0, 3));
        assert_eq!(LENGTH_CODES[10], (264, 0, 10));
        assert_eq!(LENGTH_CODES[12], (265, 1, 11));
        assert_eq!(LENGTH_CODES[34], (272, 2, 31));
        assert_eq!(LENGTH_CODES[130], (280, 4, 115));
        assert_eq!(LENGTH_CODES[257], (284, 5, 227));
        assert_eq!(LENGTH_CODES[258], (285, 0, 258));
        for (len, &(sym, extra, base)) in LENGTH_CODES.iter().enumerate().skip(3) {
            assert!((257..=285).contains(&sym) && base as usize <= len, "{len}");
            assert!(len - (base as usize) < 1 << extra, "{len}");
        }
    }

    #[test]
    fn code_length_runs_expand_back() {
        let mut rng = SplitMix64::new(5);
        for _ in 0..200 {
            let n = 1 + (rng.next_u64() % 300) as usize;
            let mut lengths = Vec::with_capacity(n);
            while lengths.len() < n {
                let l = (rng.next_u64() % 16) as u8;
                let l = if rng.next_u64().is_multiple_of(3) {
                    0
                } else {
                    l
                };
                let repeat = 1 + (rng.next_u64() % 40) as usize;
                lengths.extend(std::iter::repeat_n(l, repeat.min(n - lengths.len())));
            }
            let mut expanded: Vec<u8> = Vec::new();
            for (s, extra) in run_length_code(&lengths) {
                match s {
                    16 => {
                        assert!(extra < 4);
                        let last = *expanded.last().expect("a length to repeat");
                        expanded.extend(std::iter::repeat_n(last, 3 + extra as usize));
                    }
                    17 => expanded.extend(std::iter::repeat_n(0, 3 + extra as usize)),
                    18 => expanded.extend(std::iter::repeat_n(0, 11 + extra as usize)),
                    l => expanded.push(l),
                }
            }
            assert_eq!(expanded, lengths);
        }
    }

    #[test]
    fn adler32_combines_as_one_pass() {
        let mut rng = SplitMix64::new(9);
        let data: Vec<u8> = (0..200_000).map(|_| rng.next_u64() as u8).collect();
        let whole = simd_adler32::adler32(&data.as_slice());
        for split in [0, 1, 65520, 65521, 65522, 131_042, 199_999, 200_000] {
            let (a, b) = data.split_at(split);
            let combined = adler32_combine(
                simd_adler32::adler32(&a),
                simd_adler32::adler32(&b),
                b.len(),
            );
            assert_eq!(combined, whole, "split at {split}");
        }
        // All 0xff bytes push both sums to their largest values.
        let ones = vec![0xffu8; 70_000];
        let (a, b) = ones.split_at(4000);
        assert_eq!(
            adler32_combine(
                simd_adler32::adler32(&a),
                simd_adler32::adler32(&b),
                b.len()
            ),
            simd_adler32::adler32(&ones.as_slice())
        );
    }
}
