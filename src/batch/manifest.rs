//! The batch manifest: one record per job, rewritten after every job (temporary file, then rename), so
//! a batch killed at any point leaves a valid manifest of the jobs it finished. `--resume` reads it
//! back, checks that it belongs to the jobs file (each record carries a hash of its job's table), and
//! hands over the finished jobs to skip.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::report::JobImages;
use crate::radiosity::fingerprint::fnv1a64;

/// One job's entry in the manifest.
#[derive(Serialize, Deserialize, Clone, Debug)]
pub struct JobRecord {
    pub index: usize,
    /// FNV-1a 64 (hex) of the job's `[[job]]` table, keys sorted: what `--resume` checks.
    #[serde(default)]
    pub job_key: String,
    pub scene: String,
    /// "ok" or "failed".
    pub status: String,
    pub error: Option<String>,
    pub outputs: Vec<String>,
    pub seconds: f64,
    /// What the run measured (`run::RunStats` as JSON).
    pub stats: serde_json::Value,
    /// Whether the form factors / solution came from an earlier job of this batch.
    pub reused_form_factors: bool,
    pub reused_solution: bool,
    /// The job's part of the `--report` page, when one was asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub report: Option<JobImages>,
    /// True when `--resume` kept this record from an earlier run instead of running the job.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub from_earlier_run: bool,
}

/// The manifest file's shape.
#[derive(Serialize, Deserialize, Debug)]
pub struct Manifest {
    pub jobs_file: String,
    pub shard: Option<String>,
    pub jobs: Vec<JobRecord>,
}

/// Why `--resume` refuses a manifest.
#[derive(Debug, thiserror::Error)]
pub enum ResumeError {
    #[error("{}: cannot read manifest to resume: {source}", path.display())]
    Read { path: PathBuf, source: std::io::Error },
    #[error("{}:{line}: not a radray batch manifest: {message}", path.display())]
    Parse { path: PathBuf, line: usize, message: String },
    #[error("{}: does not match {jobs_file}: {what}; run without --resume (or with another --manifest) to start again", path.display())]
    Mismatch { path: PathBuf, jobs_file: String, what: String },
}

/// The hash `--resume` compares: FNV-1a 64 of the job's table as JSON with sorted keys (so comments,
/// spacing and key order in the jobs file do not matter, but every value does).
pub fn job_key(table: &toml::Value) -> String {
    let canonical = serde_json::to_value(table).map(|v| v.to_string()).unwrap_or_default();
    format!("{:016x}", fnv1a64(canonical.as_bytes()))
}

/// The finished jobs of an earlier run's manifest at `path` (none if there is no file), checked
/// against the jobs file's `job_keys`: a record of a job that is not in the jobs file, or whose table
/// changed, refuses the resume. Failed jobs, and jobs an output of which is missing, are left to run.
pub fn finished_jobs(path: &Path, jobs_file: &Path, job_keys: &[String]) -> Result<Vec<JobRecord>, ResumeError> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(source) => return Err(ResumeError::Read { path: path.to_path_buf(), source }),
    };
    let manifest: Manifest = serde_json::from_str(&text).map_err(|e| ResumeError::Parse {
        path: path.to_path_buf(),
        line: e.line(),
        message: e.to_string(),
    })?;
    let mismatch = |what: String| ResumeError::Mismatch {
        path: path.to_path_buf(),
        jobs_file: jobs_file.display().to_string(),
        what,
    };
    let mut done = Vec::new();
    for record in manifest.jobs {
        let Some(key) = job_keys.get(record.index) else {
            return Err(mismatch(format!(
                "it records job {} but the jobs file has {} jobs",
                record.index,
                job_keys.len()
            )));
        };
        if record.job_key != *key {
            return Err(mismatch(format!("job {} ({}) is not the same job any more", record.index, record.scene)));
        }
        if record.status == "ok" && record.outputs.iter().all(|o| Path::new(o).is_file()) {
            done.push(record);
        }
    }
    Ok(done)
}

/// The manifest of a running batch: its records, each serialised once, and the file they go to.
pub struct ManifestWriter {
    path: PathBuf,
    header: String,
    /// (job index, the record as pretty JSON), in job order.
    records: Vec<(usize, String)>,
}

impl ManifestWriter {
    pub fn new(path: &Path, jobs_file: &str, shard: Option<&str>) -> Self {
        let header = format!(
            "{{\n  \"jobs_file\": {},\n  \"shard\": {},\n  \"jobs\": [",
            serde_json::Value::from(jobs_file),
            shard.map_or(serde_json::Value::Null, serde_json::Value::from)
        );
        ManifestWriter { path: path.to_path_buf(), header, records: Vec::new() }
    }

    /// Adds (or replaces) the record of a job.
    pub fn add(&mut self, record: &JobRecord) -> Result<(), serde_json::Error> {
        let json = serde_json::to_string_pretty(record)?.replace('\n', "\n    ");
        match self.records.binary_search_by_key(&record.index, |(i, _)| *i) {
            Ok(at) => self.records[at].1 = json,
            Err(at) => self.records.insert(at, (record.index, json)),
        }
        Ok(())
    }

    fn text(&self) -> String {
        let mut text = self.header.clone();
        for (n, (_, json)) in self.records.iter().enumerate() {
            text.push_str(if n == 0 { "\n    " } else { ",\n    " });
            text.push_str(json);
        }
        text.push_str(if self.records.is_empty() { "]\n}\n" } else { "\n  ]\n}\n" });
        text
    }

    /// Writes the manifest to a temporary file and renames it into place: a process killed at any
    /// moment leaves the previous or the new manifest, whole. No fsync (a kill does not lose the page
    /// cache; `finish` syncs).
    pub fn write(&self) -> std::io::Result<()> {
        let tmp = crate::output::temporary_path(&self.path);
        let result = std::fs::write(&tmp, self.text()).and_then(|()| std::fs::rename(&tmp, &self.path));
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        result
    }

    /// The last write, synced to disk.
    pub fn finish(&self) -> std::io::Result<()> {
        crate::output::write_atomically(&self.path, self.text().as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(index: usize, key: &str, status: &str, outputs: Vec<String>) -> JobRecord {
        JobRecord {
            index,
            job_key: key.to_string(),
            scene: "s.toml".into(),
            status: status.into(),
            error: None,
            outputs,
            seconds: 1.0,
            stats: serde_json::json!({"elements": 3}),
            reused_form_factors: false,
            reused_solution: false,
            report: None,
            from_earlier_run: false,
        }
    }

    #[test]
    fn written_manifest_reads_back_in_job_order() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.json");
        let mut writer = ManifestWriter::new(&path, "jobs \"x\".toml", None);
        writer.write().unwrap();
        let empty: Manifest = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert!(empty.jobs.is_empty());
        writer.add(&record(2, "b", "ok", vec![])).unwrap();
        writer.add(&record(0, "a", "failed", vec![])).unwrap();
        writer.write().unwrap();
        let m: Manifest = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_eq!(m.jobs_file, "jobs \"x\".toml");
        assert_eq!(m.jobs.iter().map(|r| r.index).collect::<Vec<_>>(), vec![0, 2]);
        assert_eq!(m.jobs[1].stats["elements"], 3);
    }

    #[test]
    fn resume_keeps_finished_jobs_and_refuses_a_changed_jobs_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.json");
        let output = dir.path().join("a.png");
        std::fs::write(&output, b"png").unwrap();
        let mut writer = ManifestWriter::new(&path, "jobs.toml", None);
        writer.add(&record(0, "k0", "ok", vec![output.display().to_string()])).unwrap();
        writer.add(&record(1, "k1", "failed", vec![])).unwrap();
        writer.add(&record(2, "k2", "ok", vec![dir.path().join("gone.png").display().to_string()])).unwrap();
        writer.write().unwrap();
        let keys: Vec<String> = ["k0", "k1", "k2", "k3"].iter().map(|s| s.to_string()).collect();
        let done = finished_jobs(&path, Path::new("jobs.toml"), &keys).unwrap();
        assert_eq!(done.iter().map(|r| r.index).collect::<Vec<_>>(), vec![0], "failed and missing outputs rerun");
        let changed: Vec<String> = ["k0", "other", "k2"].iter().map(|s| s.to_string()).collect();
        let e = finished_jobs(&path, Path::new("jobs.toml"), &changed).unwrap_err();
        assert!(e.to_string().contains("job 1 (s.toml) is not the same job"), "{e}");
        let e = finished_jobs(&path, Path::new("jobs.toml"), &keys[..2]).unwrap_err();
        assert!(e.to_string().contains("records job 2 but the jobs file has 2 jobs"), "{e}");
        assert!(finished_jobs(&dir.path().join("none.json"), Path::new("j"), &keys).unwrap().is_empty());
        std::fs::write(&path, "{\"jobs\": [").unwrap();
        assert!(matches!(finished_jobs(&path, Path::new("j"), &keys), Err(ResumeError::Parse { .. })));
    }

    #[test]
    fn job_key_ignores_key_order_but_not_values() {
        let a: toml::Value = toml::from_str("scene = \"s\"\nwidth = 4").unwrap();
        let b: toml::Value = toml::from_str("width = 4\n# note\nscene = \"s\"").unwrap();
        let c: toml::Value = toml::from_str("scene = \"s\"\nwidth = 5").unwrap();
        assert_eq!(job_key(&a), job_key(&b));
        assert_ne!(job_key(&a), job_key(&c));
    }
}
