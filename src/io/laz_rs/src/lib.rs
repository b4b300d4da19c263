// SPDX-License-Identifier: MIT
//! kissm's C ABI over the `laz` crate: the LAZ point records of a file already in memory, decompressed
//! into the caller's buffer. src/io/laz_reader.cpp is the only caller; it has parsed the LAS header and
//! found the LASzip VLR. Every function catches panics (a panic must not cross into C++) and reports
//! errors as text; nothing is printed (a silent panic hook is installed in this library's own copy of
//! the Rust runtime, which libkissm keeps private).
//!
//! Before `laz` sees the data, `open` checks what `laz` would allocate from untrusted sizes: the chunk
//! table's entry count and, for LAS 1.4's layered chunks, every layer's byte count, each against the
//! bytes that are in the file, so that memory stays bounded by the file and hostile sizes fail as errors.
//!
//! `laz`, like LASzip, decodes GPS time recursively (a "switch sequence" symbol reads again), and corrupt
//! data can repeat that symbol until the stack overflows, which no error handling survives. Valid data
//! recurse once or twice. So the layered formats are decompressed without their GPS time layer (kissm
//! reads x, y, z and the flags only), and for the point-wise formats, whose fields share one stream, every
//! byte `laz` reads goes through `Source`, which fails the read once the stack below `kissmlaz_read` has
//! grown past `STACK_BUDGET`: the recursion then unwinds as an I/O error.

use std::cell::Cell;
use std::io::{Cursor, Read, Seek, SeekFrom};
use std::os::raw::c_char;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;

use laz::laszip::{LazItemType, LazVlr};
use laz::{DecompressionSelection, LasZipDecompressor};

/// How deep the stack may grow below `kissmlaz_read` while `laz` decodes. Valid data use a few kilobytes;
/// a corrupt GPS time stream recurses by at most a few hundred frames between two byte reads, which
/// stays far inside the 2 MB of the smallest usual thread stack (Rust's default) above this budget.
const STACK_BUDGET: usize = 256 * 1024;

thread_local! {
    /// The stack address at the entry of the `kissmlaz_read` running on this thread (0: none).
    static STACK_TOP: Cell<usize> = const { Cell::new(0) };
}

fn stack_address() -> usize {
    let marker = 0u8;
    std::hint::black_box(&marker) as *const u8 as usize
}

/// The file's bytes as `laz` reads them, refusing to read once the decoder nests too deeply.
struct Source(Cursor<&'static [u8]>);

impl Read for Source {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let top = STACK_TOP.with(Cell::get);
        if top != 0 && top.saturating_sub(stack_address()) > STACK_BUDGET {
            return Err(std::io::Error::other("the compressed data nest too deeply (corrupt GPS time stream)"));
        }
        self.0.read(buf)
    }
}

impl Seek for Source {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.0.seek(pos)
    }
}

/// An open decompressor over the caller's bytes (which must outlive it).
pub struct Reader {
    decompressor: LasZipDecompressor<'static, Source>,
    record_length: usize,
}

fn quiet_panics() {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| std::panic::set_hook(Box::new(|_| {})));
}

fn write_message(text: &str, msg: *mut c_char, cap: usize) {
    if msg.is_null() || cap == 0 {
        return;
    }
    let n = text.len().min(cap - 1);
    // SAFETY: the caller passes a buffer of `cap` bytes.
    unsafe {
        std::ptr::copy_nonoverlapping(text.as_ptr(), msg as *mut u8, n);
        *msg.add(n) = 0;
    }
}

fn le_u32(data: &[u8], at: u64) -> Option<u32> {
    let at = usize::try_from(at).ok()?;
    let b = data.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

fn le_i64(data: &[u8], at: u64) -> Option<i64> {
    let at = usize::try_from(at).ok()?;
    let b = data.get(at..at.checked_add(8)?)?;
    let mut a = [0u8; 8];
    a.copy_from_slice(b);
    Some(i64::from_le_bytes(a))
}

/// The chunk table's entry count must not exceed the compressed bytes (every chunk takes at least one),
/// since `laz` reserves an entry per count before reading them. Where `laz` looks for the table: the
/// offset at the start of the point data, or else the file's last 8 bytes.
fn check_chunk_table(data: &[u8], point_offset: u64) -> Result<(), String> {
    let len = data.len() as u64;
    let mut table = le_i64(data, point_offset).ok_or("truncated: no LAZ chunk table offset after the header")?;
    if table <= point_offset as i64 {
        table = le_i64(data, len.saturating_sub(8)).unwrap_or(0);
        if table <= point_offset as i64 {
            return Ok(()); // no table: `laz` reads without one where it can, else reports it missing
        }
    }
    if let Some(chunks) = le_u32(data, table as u64 + 4) {
        if u64::from(chunks) > len - point_offset {
            return Err(format!(
                "the LAZ chunk table lists {chunks} chunks, more than the {} bytes of point data hold",
                len - point_offset
            ));
        }
    }
    Ok(())
}

/// How many layers (each with a u32 byte count at the start of a chunk) an item has in LAS 1.4's layered
/// compression (LASzip's specification of point 14, RGB 14, NIR and wave packet items).
fn layers_of(item: &LazItemType) -> Option<u64> {
    match item {
        LazItemType::Point14 => Some(9),
        LazItemType::RGB14 | LazItemType::WavePacket14 => Some(1),
        LazItemType::RGBNIR14 => Some(2),
        LazItemType::Byte14(n) => Some(u64::from(*n)),
        _ => None,
    }
}

/// Walks the layered chunks as `laz` will read them (first point raw, point count, layer sizes, layers)
/// and checks that every layer lies inside the file, before `laz` allocates a buffer of each layer's size.
fn check_layers(data: &[u8], vlr: &LazVlr, point_offset: u64, record_length: u64, count: u64) -> Result<(), String> {
    let mut layers = 0u64;
    for item in vlr.items() {
        layers += layers_of(&item.item_type()).ok_or("a LAS 1.4 layered LAZ file lists a LAS 1.0-1.3 item")?;
    }
    let len = data.len() as u64;
    let mut pos = point_offset + 8; // after the chunk table offset
    let mut points = 0u64;
    while points < count {
        let sizes_at = pos + record_length + 4;
        let in_chunk =
            le_u32(data, pos + record_length).ok_or("truncated LAZ data: a chunk's point count is missing")?;
        let fixed = if vlr.uses_variable_size_chunks() { u64::from(in_chunk) } else { u64::from(vlr.chunk_size()) };
        if fixed == 0 {
            return Err("a LAZ chunk holds no points".into());
        }
        let mut end = sizes_at + 4 * layers;
        for k in 0..layers {
            let size = le_u32(data, sizes_at + 4 * k).ok_or("truncated LAZ data: a chunk's layer sizes are missing")?;
            end = end.saturating_add(u64::from(size));
        }
        if end > len {
            return Err(format!("a LAZ chunk's layers end at byte {end}, beyond the file's {len} bytes"));
        }
        pos = end;
        points = points.saturating_add(fixed);
    }
    Ok(())
}

fn open(
    data: &'static [u8],
    point_offset: u64,
    vlr: &[u8],
    record_length: u16,
    count: u64,
) -> Result<Box<Reader>, String> {
    // The compressor type (the payload's first u16; `laz` keeps its field private): 1 point-wise in one
    // chunk, 2 point-wise chunked, 3 layered chunked (LAS 1.4 formats 6-10).
    let compressor = vlr.get(..2).map(|b| u16::from_le_bytes([b[0], b[1]])).unwrap_or(0);
    let vlr = LazVlr::from_buffer(vlr).map_err(|e| format!("the LASzip VLR is malformed: {e}"))?;
    if vlr.items_size() != u64::from(record_length) {
        return Err(format!(
            "the LASzip VLR describes {}-byte records, the header {record_length}-byte ones",
            vlr.items_size()
        ));
    }
    match vlr.items().first().map(|i| i.item_type()) {
        Some(LazItemType::Point10) | Some(LazItemType::Point14) => {}
        _ => return Err("the LASzip VLR's first item is not a point (x y z) item".into()),
    }
    if point_offset >= data.len() as u64 {
        return Err("truncated: no LAZ point data after the header".into());
    }
    if compressor != 1 {
        check_chunk_table(data, point_offset)?;
    }
    if compressor == 3 {
        check_layers(data, &vlr, point_offset, u64::from(record_length), count)?;
    }
    let mut cursor = Cursor::new(data);
    cursor.set_position(point_offset);
    // x, y, z and the flags byte (withheld) are all kissm reads; layered files skip the other layers.
    let selection = DecompressionSelection::xy_returns_channel().decompress_z().decompress_flags();
    let decompressor =
        LasZipDecompressor::selective(Source(cursor), vlr, selection).map_err(|e| format!("LAZ data: {e}"))?;
    Ok(Box::new(Reader { decompressor, record_length: usize::from(record_length) }))
}

/// Opens a decompressor over the `len` bytes at `data` (the whole file, which must stay alive and
/// unchanged until `kissmlaz_close`), with points at `point_offset`, the LASzip VLR's payload
/// `vlr[..vlr_len]`, records of `record_length` bytes and `count` points. Returns the reader, or null with
/// the reason in `msg` (`cap` bytes, NUL-terminated).
///
/// # Safety
/// `data`, `vlr` and `msg` must point to `len`, `vlr_len` and `cap` valid bytes.
#[no_mangle]
pub unsafe extern "C" fn kissmlaz_open(
    data: *const u8,
    len: usize,
    point_offset: u64,
    vlr: *const u8,
    vlr_len: usize,
    record_length: u16,
    count: u64,
    msg: *mut c_char,
    cap: usize,
) -> *mut Reader {
    quiet_panics();
    if data.is_null() || vlr.is_null() {
        write_message("null buffer", msg, cap);
        return std::ptr::null_mut();
    }
    // SAFETY: the caller keeps the buffers alive (see above).
    let data: &'static [u8] = std::slice::from_raw_parts(data, len);
    let vlr = std::slice::from_raw_parts(vlr, vlr_len);
    match catch_unwind(AssertUnwindSafe(|| open(data, point_offset, vlr, record_length, count))) {
        Ok(Ok(reader)) => Box::into_raw(reader),
        Ok(Err(text)) => {
            write_message(&text, msg, cap);
            std::ptr::null_mut()
        }
        Err(_) => {
            write_message("the LAZ decompressor failed on this data (internal panic)", msg, cap);
            std::ptr::null_mut()
        }
    }
}

/// Decompresses the next `n` records into `out` (`n` * record length bytes). Returns 0, or -1 with the
/// reason in `msg`; after an error the reader must only be closed.
///
/// # Safety
/// `reader` from `kissmlaz_open`; `out` holds `n` records; `msg` holds `cap` bytes.
#[no_mangle]
pub unsafe extern "C" fn kissmlaz_read(
    reader: *mut Reader,
    out: *mut u8,
    n: usize,
    msg: *mut c_char,
    cap: usize,
) -> i32 {
    if reader.is_null() || out.is_null() {
        write_message("null reader or buffer", msg, cap);
        return -1;
    }
    let reader = &mut *reader;
    let Some(bytes) = n.checked_mul(reader.record_length) else {
        write_message("record buffer size overflows", msg, cap);
        return -1;
    };
    let out = std::slice::from_raw_parts_mut(out, bytes);
    STACK_TOP.with(|top| top.set(stack_address()));
    let result = catch_unwind(AssertUnwindSafe(|| reader.decompressor.decompress_many(out)));
    STACK_TOP.with(|top| top.set(0));
    match result {
        Ok(Ok(())) => 0,
        Ok(Err(e)) => {
            write_message(&format!("corrupt or truncated LAZ data: {e}"), msg, cap);
            -1
        }
        Err(_) => {
            write_message("corrupt LAZ data (the decompressor failed: internal panic)", msg, cap);
            -1
        }
    }
}

/// Frees a reader from `kissmlaz_open` (null is fine).
///
/// # Safety
/// `reader` from `kissmlaz_open`, closed once.
#[no_mangle]
pub unsafe extern "C" fn kissmlaz_close(reader: *mut Reader) {
    if !reader.is_null() {
        let _ = catch_unwind(AssertUnwindSafe(|| drop(Box::from_raw(reader))));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn source_refuses_to_read_when_the_stack_is_deep() {
        let data: &'static [u8] = b"abcdef";
        let mut source = Source(Cursor::new(data));
        let mut byte = [0u8; 1];
        assert_eq!(source.read(&mut byte).unwrap(), 1); // no kissmlaz_read on this thread: no limit
                                                        // As if kissmlaz_read had started far above: the decoder is deeper than the budget.
        STACK_TOP.with(|top| top.set(stack_address() + STACK_BUDGET + 4096));
        let err = source.read(&mut byte).unwrap_err();
        assert!(err.to_string().contains("nest too deeply"), "{err}");
        STACK_TOP.with(|top| top.set(stack_address() + 1024));
        assert_eq!(source.read(&mut byte).unwrap(), 1);
        STACK_TOP.with(|top| top.set(0));
    }

    #[test]
    fn open_reports_a_malformed_vlr() {
        let data: &'static [u8] = &[0u8; 64];
        let mut msg = [0 as c_char; 128];
        // SAFETY: the buffers are valid for the lengths given.
        let reader = unsafe { kissmlaz_open(data.as_ptr(), 64, 0, data.as_ptr(), 4, 20, 1, msg.as_mut_ptr(), 128) };
        assert!(reader.is_null());
        // SAFETY: kissmlaz_open wrote a NUL-terminated message.
        let text = unsafe { std::ffi::CStr::from_ptr(msg.as_ptr()) }.to_string_lossy().into_owned();
        assert!(text.contains("LASzip VLR"), "{text}");
    }
}
