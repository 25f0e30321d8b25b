//! Content keys of stage instances.
//!
//! `key = SHA-256( canonical JSON of {salt, stage, version, params, inputs} )`, hex encoded.
//! Canonical JSON: object keys sorted (serde_json's map is ordered), no whitespace, floats in
//! their shortest round-trip form (ryu), integers as integers. Only the parameters a stage
//! reads go into `params`, so a parameter the stage ignores cannot change its key.

use serde_json::{json, Value};
use sha2::{Digest, Sha256};

/// Global salt: bump it to invalidate every cached artifact at once (store format change).
pub const STORE_SALT: &str = "wearcoef-store-1";

/// Canonical JSON text of a value (sorted keys, compact, shortest round-trip floats).
pub fn canonical_json(value: &Value) -> String {
    // serde_json::Map is a BTreeMap (the `preserve_order` feature is not enabled), so keys
    // serialise in sorted order at every depth.
    serde_json::to_string(value).expect("a serde_json::Value always serialises")
}

/// Hex SHA-256 of bytes.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// Lower-case hex of bytes.
pub fn hex(bytes: &[u8]) -> String {
    const DIGITS: &[u8; 16] = b"0123456789abcdef";
    let mut s = String::with_capacity(bytes.len() * 2);
    for b in bytes {
        s.push(DIGITS[(b >> 4) as usize] as char);
        s.push(DIGITS[(b & 15) as usize] as char);
    }
    s
}

/// The key of a stage instance.
pub fn instance_key(stage: &str, version: u32, params: &Value, inputs: &[String]) -> String {
    let doc = json!({
        "salt": STORE_SALT,
        "stage": stage,
        "version": version,
        "params": params,
        "inputs": inputs,
    });
    sha256_hex(canonical_json(&doc).as_bytes())
}

/// Streaming SHA-256 of a file.
pub fn sha256_file(path: &std::path::Path) -> std::io::Result<(String, u64)> {
    use std::io::Read;
    let mut file = std::fs::File::open(path)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 20];
    let mut total = 0u64;
    loop {
        let read = file.read(&mut buf)?;
        if read == 0 {
            break;
        }
        total += read as u64;
        hasher.update(&buf[..read]);
    }
    Ok((hex(&hasher.finalize()), total))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn canonical_json_sorts_keys_and_keeps_shortest_floats() {
        let a = json!({"b": 0.1, "a": {"z": 1, "y": 1e-10}, "c": 2.0});
        assert_eq!(
            canonical_json(&a),
            r#"{"a":{"y":1e-10,"z":1},"b":0.1,"c":2.0}"#
        );
    }

    #[test]
    fn sha256_matches_a_known_vector() {
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn key_depends_on_every_part() {
        let p = json!({"n": 64});
        let k = instance_key("surface", 1, &p, &[]);
        assert_eq!(k.len(), 64);
        assert_ne!(k, instance_key("surface", 2, &p, &[]));
        assert_ne!(k, instance_key("contact", 1, &p, &[]));
        assert_ne!(k, instance_key("surface", 1, &json!({"n": 65}), &[]));
        assert_ne!(k, instance_key("surface", 1, &p, &["x".to_string()]));
        assert_eq!(k, instance_key("surface", 1, &json!({"n": 64}), &[]));
    }
}
