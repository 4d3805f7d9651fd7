//! A gzip stream of parts repeated many times, for the hostile-input tests of the readers and
//! the command line (included with `#[path]`): small files that expand a thousandfold.

use std::io::Write;

/// The gzip (level 6) of each `(part, times)` written `times` times, in order.
pub fn gzip<P: AsRef<[u8]>>(parts: impl IntoIterator<Item = (P, usize)>) -> Vec<u8> {
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::new(6));
    for (part, times) in parts {
        let part = part.as_ref();
        // Written a block of repeats at a time: a write per repeat of a one-byte part costs
        // the encoder a buffer each, minutes for 10⁷ of them.
        let per_block = (1 << 20) / part.len().max(1) + 1;
        let block = part.repeat(per_block.min(times));
        let mut left = times;
        while left > 0 {
            let n = left.min(per_block);
            gz.write_all(&block[..n * part.len()]).unwrap();
            left -= n;
        }
    }
    gz.finish().unwrap()
}
