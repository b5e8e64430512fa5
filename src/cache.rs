//! A memory-bounded cache, least recently used first out: what a batch keeps between its jobs (form
//! factors, solutions) is weighed in bytes and never holds more than its budget. Keys are the 64-bit
//! fingerprints of what a value depends on.

/// Values by key, at most `budget_bytes` of them by their stated sizes; inserting evicts the least
/// recently used (inserted or read) entries until the new one fits.
#[derive(Debug)]
pub struct Lru<V> {
    budget_bytes: u64,
    used_bytes: u64,
    /// Each entry's last use on `clock`; a batch keeps tens to hundreds of entries, so the linear
    /// scans cost nothing next to a job.
    entries: Vec<Entry<V>>,
    clock: u64,
}

#[derive(Debug)]
struct Entry<V> {
    key: u64,
    value: V,
    bytes: u64,
    last_use: u64,
}

/// What a batch keeps between its jobs unless told otherwise (`cache_memory`).
pub const DEFAULT_BUDGET_BYTES: u64 = 2 << 30;

impl<V> Default for Lru<V> {
    /// A cache that keeps nothing.
    fn default() -> Self {
        Lru::new(0)
    }
}

impl<V> Lru<V> {
    pub fn new(budget_bytes: u64) -> Self {
        Lru { budget_bytes, used_bytes: 0, entries: Vec::new(), clock: 0 }
    }

    /// The value under `key`, which becomes the most recently used.
    pub fn get(&mut self, key: u64) -> Option<&V> {
        self.clock += 1;
        let clock = self.clock;
        let entry = self.entries.iter_mut().find(|e| e.key == key)?;
        entry.last_use = clock;
        Some(&entry.value)
    }

    /// Keeps `value` (of `bytes`) under `key`, replacing an older value, after evicting the least
    /// recently used entries until it fits. A value larger than the whole budget is not kept: the
    /// return value says whether it was.
    pub fn insert(&mut self, key: u64, value: V, bytes: u64) -> bool {
        self.remove(key);
        if bytes > self.budget_bytes {
            return false;
        }
        self.make_room(bytes);
        self.clock += 1;
        self.used_bytes += bytes;
        self.entries.push(Entry { key, value, bytes, last_use: self.clock });
        true
    }

    /// Evicts the least recently used entries until `bytes` more fit in the budget (all of them if
    /// `bytes` exceeds it): called before building a large value, so that the old ones are freed first.
    pub fn make_room(&mut self, bytes: u64) {
        while self.used_bytes + bytes > self.budget_bytes {
            let Some(oldest) = self.entries.iter().enumerate().min_by_key(|(_, e)| e.last_use).map(|(i, _)| i) else {
                break;
            };
            let entry = self.entries.swap_remove(oldest);
            self.used_bytes -= entry.bytes;
        }
    }

    fn remove(&mut self, key: u64) {
        if let Some(i) = self.entries.iter().position(|e| e.key == key) {
            let entry = self.entries.swap_remove(i);
            self.used_bytes -= entry.bytes;
        }
    }

    /// Bytes held, by the entries' stated sizes.
    pub fn used_bytes(&self) -> u64 {
        self.used_bytes
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// Parses a memory size: a number of bytes, or a number with a unit B, KB, MB, GB (powers of 1000) or
/// KiB, MiB, GiB (powers of 1024), e.g. `"512 MiB"`, `"2GB"`.
pub fn parse_bytes(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(t.len());
    let (number, unit) = (t[..split].trim(), t[split..].trim());
    let value: f64 = number.parse().map_err(|_| format!("`{text}` is not a memory size such as \"512 MiB\""))?;
    let scale: f64 = match unit.to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "kb" => 1e3,
        "mb" => 1e6,
        "gb" => 1e9,
        "kib" => 1024.0,
        "mib" => 1024.0 * 1024.0,
        "gib" => 1024.0 * 1024.0 * 1024.0,
        _ => return Err(format!("`{text}`: unknown unit `{unit}` (use B, KB, MB, GB, KiB, MiB or GiB)")),
    };
    let bytes = value * scale;
    if !bytes.is_finite() || bytes >= u64::MAX as f64 {
        return Err(format!("`{text}` is too large"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn least_recently_used_entry_is_evicted_first() {
        let mut cache = Lru::new(100);
        assert!(cache.insert(1, "a", 40));
        assert!(cache.insert(2, "b", 40));
        assert_eq!(cache.get(1), Some(&"a")); // 2 is now the least recently used
        assert!(cache.insert(3, "c", 40));
        assert_eq!(cache.get(2), None, "2 was evicted");
        assert_eq!(cache.get(1), Some(&"a"));
        assert_eq!(cache.get(3), Some(&"c"));
        assert_eq!(cache.used_bytes(), 80);
        // Replacing a key frees its old size first.
        assert!(cache.insert(3, "c2", 70));
        assert_eq!((cache.len(), cache.used_bytes()), (1, 70), "1 (40) had to go for 70 more");
        assert_eq!(cache.get(3), Some(&"c2"));
    }

    #[test]
    fn a_value_larger_than_the_budget_is_not_kept_and_the_budget_holds() {
        let mut cache = Lru::new(100);
        assert!(cache.insert(1, 1, 30));
        assert!(!cache.insert(2, 2, 101));
        assert_eq!(cache.get(2), None);
        assert_eq!(cache.get(1), Some(&1), "a refused value evicts nothing");
        for key in 10..100 {
            cache.insert(key, key, 7 + key % 13);
            assert!(cache.used_bytes() <= 100);
        }
        let mut empty: Lru<u8> = Lru::new(0);
        assert!(!empty.insert(1, 1, 1) && empty.is_empty());
    }

    #[test]
    fn make_room_frees_the_oldest_before_a_large_build() {
        let mut cache = Lru::new(100);
        cache.insert(1, (), 50);
        cache.insert(2, (), 50);
        cache.make_room(30);
        assert_eq!((cache.len(), cache.used_bytes()), (1, 50));
        assert!(cache.get(2).is_some());
    }

    #[test]
    fn memory_sizes_parse_with_units() {
        assert_eq!(parse_bytes("1024"), Ok(1024));
        assert_eq!(parse_bytes("512 MiB"), Ok(512 << 20));
        assert_eq!(parse_bytes("2GB"), Ok(2_000_000_000));
        assert_eq!(parse_bytes("1.5 KiB"), Ok(1536));
        assert!(parse_bytes("lots").is_err());
        assert!(parse_bytes("3 TB").unwrap_err().contains("unknown unit"));
    }
}
