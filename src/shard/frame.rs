//! The framing the shard file and the plan file share: an 8-byte mark, the format version
//! (`u32`), the JSON header's length (`u32`) and the header, the body, and a CRC-32 (IEEE) of
//! every byte before it, little-endian throughout.

/// The file's bytes: `magic`, `version`, `json` with its length, the body `write_body`
/// appends (about `body_len` bytes), and the checksum.
pub fn encode(
    magic: &[u8; 8],
    version: u32,
    json: &[u8],
    body_len: usize,
    write_body: impl FnOnce(&mut Vec<u8>),
) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + json.len() + body_len + 4);
    out.extend_from_slice(magic);
    out.extend_from_slice(&version.to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(json);
    write_body(&mut out);
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}
