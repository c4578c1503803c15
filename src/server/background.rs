//! A server on a thread of its own, with its own runtime: for tests, examples and
//! programs that embed winged next to other work.

use std::future::Future;
use std::io;
use std::net::SocketAddr;
use std::thread::JoinHandle;

use axum::Router;
use tokio::net::TcpListener;
use tokio::sync::oneshot;

use super::{App, listen, serve_on};

/// A running server. Dropping it (or [`Background::stop`]) stops it gracefully: event
/// streams end, requests in flight are answered, the world's owner closes its journal.
pub struct Background {
    /// The address it listens on.
    pub addr: SocketAddr,
    stop: Option<oneshot::Sender<()>>,
    thread: Option<JoinHandle<io::Result<()>>>,
}

impl Background {
    /// Binds `addr` (port 0 for an ephemeral one) and serves the application `make`
    /// builds; `make` runs on the server's runtime. Returns once it listens.
    pub fn start(
        addr: SocketAddr,
        make: impl FnOnce() -> io::Result<App> + Send + 'static,
    ) -> io::Result<Background> {
        Self::spawn(addr, move |listener, stop| async move {
            serve_on(listener, make()?, async move {
                let _ = stop.await;
            })
            .await
        })
    }

    /// Binds `addr` and serves a plain router (no world of its own) within the default
    /// connection limits.
    pub fn router(addr: SocketAddr, router: Router) -> io::Result<Background> {
        Self::spawn(addr, move |listener, stop| async move {
            listen::serve(listener, router, listen::Settings::default(), async move {
                let _ = stop.await;
            })
            .await
        })
    }

    /// `http://ADDR`.
    pub fn base(&self) -> String {
        format!("http://{}", self.addr)
    }

    /// Stops the server and waits for it; its error, if serving failed.
    pub fn stop(mut self) -> io::Result<()> {
        self.finish()
    }

    fn finish(&mut self) -> io::Result<()> {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        match self.thread.take().map(JoinHandle::join) {
            None => Ok(()),
            Some(Ok(served)) => served,
            Some(Err(_)) => Err(io::Error::other("the server thread panicked")),
        }
    }

    fn spawn<F, Fut>(addr: SocketAddr, run: F) -> io::Result<Background>
    where
        F: FnOnce(TcpListener, oneshot::Receiver<()>) -> Fut + Send + 'static,
        Fut: Future<Output = io::Result<()>>,
    {
        let (bound_tx, bound_rx) = std::sync::mpsc::channel::<io::Result<SocketAddr>>();
        let (stop, stopped) = oneshot::channel::<()>();
        let thread = std::thread::Builder::new()
            .name("winged-server".into())
            .spawn(move || {
                let rt = tokio::runtime::Builder::new_multi_thread()
                    .worker_threads(2)
                    .enable_all()
                    .build()?;
                rt.block_on(async move {
                    let listener = match TcpListener::bind(addr).await {
                        Ok(l) => l,
                        Err(e) => {
                            let _ = bound_tx.send(Err(io::Error::new(e.kind(), e.to_string())));
                            return Err(e);
                        }
                    };
                    let _ = bound_tx.send(listener.local_addr());
                    run(listener, stopped).await
                })
            })?;
        let mut this = Background {
            addr,
            stop: Some(stop),
            thread: Some(thread),
        };
        match bound_rx.recv() {
            Ok(Ok(bound)) => {
                this.addr = bound;
                Ok(this)
            }
            Ok(Err(e)) => Err(e),
            // The thread ended before binding: its own error says why.
            Err(_) => Err(this
                .finish()
                .err()
                .unwrap_or_else(|| io::Error::other("the server stopped before listening"))),
        }
    }
}

impl Drop for Background {
    fn drop(&mut self) {
        let _ = self.finish();
    }
}
