//! `flaneur bench crowd` (ours): many walkers at once against one static HTTP server.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use super::report::write_report;
use super::walk_setup::WalkSetupArgs;
use flaneur::store::is_url;
use flaneur_bench::crowd::{self, CrowdConfig};
use flaneur_bench::nginx::{Nginx, NginxConfig};

/// Who serves the database to the crowd.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum Server {
    /// nginx from the distribution's packages, started on loopback over the file's folder.
    Nginx,
    /// `flaneur serve`'s own server, on loopback.
    Builtin,
}

/// `flaneur bench crowd`'s arguments.
#[derive(clap::Args)]
pub struct CrowdArgs {
    /// A local database file (served on loopback by `--server`), or the URL of one on any
    /// HTTP server (walked as it is; the server's CPU is then not known).
    db: String,
    #[command(flatten)]
    walk: WalkSetupArgs,
    /// Walkers at once.
    #[arg(long, default_value_t = crowd::DEFAULT_WALKERS)]
    walkers: usize,
    /// Who serves a local file.
    #[arg(long, value_enum, default_value = "nginx")]
    server: Server,
    /// Each walker's client page cache, MiB.
    #[arg(long, default_value_t = crowd::DEFAULT_CACHE_BYTES >> 20)]
    cache_mb: usize,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl CrowdArgs {
    /// Serves the database (unless it is a URL), runs the crowd and writes the report.
    pub fn run(self) -> Result<()> {
        let CrowdArgs {
            db,
            walk,
            walkers,
            server,
            cache_mb,
            out,
        } = self;
        let d = CrowdConfig::default();
        let cfg = CrowdConfig {
            walk: walk.setup(d.walk),
            walkers,
            cache_bytes: cache_mb.saturating_mul(1 << 20),
        };
        cfg.validate()?;
        let progress = format!("{walkers} walkers");
        if is_url(&db) {
            eprintln!("{progress} against {db}");
            let r = crowd::run(&db, &db, &cfg, || None)?;
            return write_report(&out, &r);
        }
        let path = PathBuf::from(&db);
        flaneur::Database::open(&path)?;
        let (Some(folder), Some(name)) = (
            path.canonicalize()
                .with_context(|| format!("{db}: cannot find it"))?
                .parent()
                .map(PathBuf::from),
            path.file_name().and_then(|n| n.to_str()).map(String::from),
        ) else {
            bail!("{db}: no file name to serve it under");
        };
        let r = match server {
            Server::Nginx => {
                let nginx = Nginx::start(&folder, NginxConfig::default())?;
                let url = nginx.url(&name);
                eprintln!("{progress} against nginx at {url}");
                crowd::run(&url, "one nginx (1 worker process)", &cfg, || {
                    nginx.cpu_seconds()
                })?
            }
            Server::Builtin => {
                let (origin, name) = crate::cli::serve::spawn(&path)
                    .with_context(|| format!("serving {db} for the crowd"))?;
                let url = format!("http://{origin}/{name}");
                eprintln!("{progress} against flaneur serve at {url}");
                crowd::run(&url, "flaneur serve (in this process)", &cfg, || None)?
            }
        };
        write_report(&out, &r)
    }
}
