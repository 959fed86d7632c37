//! nginx, the static server the network tests and benches read databases from: the
//! distribution's package, started on a free loopback port over one folder, with a
//! run folder of its own, and stopped when dropped.
//!
//! One worker process and no master (`master_process off`): the server is one process
//! whose CPU time (`/proc/PID/schedstat`) is the whole server's, and it runs as the
//! caller's user, who can read the folder.

use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::thread;
use std::time::{Duration, Instant};

use flaneur::error::{Error, Result};

/// How nginx is set up.
#[derive(Clone, Copy, Debug, Default)]
pub struct NginxConfig {
    /// `max_ranges 0`: every Range request is answered 200 with the whole file, as a
    /// server without range support would.
    pub no_ranges: bool,
}

/// nginx serving a folder on 127.0.0.1.
///
/// ```no_run
/// let server = flaneur_bench::nginx::Nginx::start(std::path::Path::new("cities"), Default::default())?;
/// println!("{}", server.url("city.flaneur"));
/// # Ok::<(), flaneur::Error>(())
/// ```
pub struct Nginx {
    child: Child,
    port: u16,
    _run: tempfile::TempDir,
}

/// The nginx binary: on the PATH, else where Debian puts it.
fn binary() -> Result<PathBuf> {
    let on_path = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join("nginx"))
            .find(|p| p.is_file())
    });
    on_path
        .or_else(|| Some(PathBuf::from("/usr/sbin/nginx")).filter(|p| p.is_file()))
        .ok_or_else(|| {
            Error::Invalid(
                "nginx is not installed (on Debian or Ubuntu: apt-get install nginx-light)".into(),
            )
        })
}

fn io(what: &str, e: std::io::Error) -> Error {
    Error::Invalid(format!("nginx: {what}: {e}"))
}

impl Nginx {
    /// Starts nginx over `root` and waits until it listens.
    pub fn start(root: &Path, config: NginxConfig) -> Result<Nginx> {
        let root = root
            .canonicalize()
            .map_err(|e| io(&format!("the folder {}", root.display()), e))?;
        let run = tempfile::tempdir().map_err(|e| io("a run folder", e))?;
        let port = TcpListener::bind("127.0.0.1:0")
            .and_then(|l| l.local_addr())
            .map_err(|e| io("a free port", e))?
            .port();
        let d = run.path().display();
        let ranges = if config.no_ranges {
            "max_ranges 0;"
        } else {
            ""
        };
        let conf = format!(
            "daemon off;\nmaster_process off;\nworker_processes 1;\npid {d}/nginx.pid;\n\
             error_log {d}/error.log warn;\nevents {{ worker_connections 1024; }}\n\
             http {{\n  access_log off;\n  client_body_temp_path {d}/body;\n  proxy_temp_path {d}/proxy;\n\
               fastcgi_temp_path {d}/fastcgi;\n  uwsgi_temp_path {d}/uwsgi;\n  scgi_temp_path {d}/scgi;\n\
               default_type application/octet-stream;\n  keepalive_requests 100000;\n\
               server {{ listen 127.0.0.1:{port}; root {root}; {ranges} }}\n}}\n",
            root = root.display()
        );
        let conf_path = run.path().join("nginx.conf");
        std::fs::write(&conf_path, conf).map_err(|e| io("writing its configuration", e))?;
        let mut child = Command::new(binary()?)
            .arg("-p")
            .arg(run.path())
            .arg("-e")
            .arg(run.path().join("error.log"))
            .arg("-c")
            .arg(&conf_path)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| io("starting it", e))?;
        let start = Instant::now();
        while TcpStream::connect(("127.0.0.1", port)).is_err() {
            let exited = child.try_wait().ok().flatten();
            if exited.is_some() || start.elapsed() > Duration::from_secs(10) {
                let _ = child.kill();
                let _ = child.wait();
                let log = std::fs::read_to_string(run.path().join("error.log")).unwrap_or_default();
                return Err(Error::Invalid(format!(
                    "nginx did not start listening on 127.0.0.1:{port}: {}",
                    log.trim()
                )));
            }
            thread::sleep(Duration::from_millis(20));
        }
        Ok(Nginx {
            child,
            port,
            _run: run,
        })
    }

    /// The URL of `name` in the served folder.
    pub fn url(&self, name: &str) -> String {
        format!("http://127.0.0.1:{}/{name}", self.port)
    }

    /// Seconds of CPU the server has used so far, when the kernel says
    /// (`/proc/PID/schedstat`, whose first field is nanoseconds on a CPU).
    pub fn cpu_seconds(&self) -> Option<f64> {
        let s = std::fs::read_to_string(format!("/proc/{}/schedstat", self.child.id())).ok()?;
        let ns: u64 = s.split_whitespace().next()?.parse().ok()?;
        Some(ns as f64 * 1e-9)
    }

    /// Stops the server now (a server gone mid-walk).
    pub fn stop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Nginx {
    fn drop(&mut self) {
        self.stop();
    }
}
