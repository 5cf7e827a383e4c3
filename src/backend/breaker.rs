//! The circuit breaker of every backend that talks to something outside this process (an
//! external process, a CPU on a bench): after `max` faults in a row its remaining trials are
//! not run, since a backend that hangs or crashes on every case would otherwise cost each case
//! its time limit, and a CPU that stopped answering would be asked again and again.

use super::Fault;

/// Faults in a row, against the limit.
#[derive(Debug, Clone)]
pub(crate) struct Breaker {
    faults_in_a_row: usize,
    max: usize,
}

impl Breaker {
    pub(crate) fn new(max: usize) -> Self {
        Breaker {
            faults_in_a_row: 0,
            max: max.max(1),
        }
    }

    /// A case answered: the count starts again.
    pub(crate) fn answered(&mut self) {
        self.faults_in_a_row = 0;
    }

    /// Counts a fault of `backend`; once `max` came in a row, why its remaining trials are not
    /// run.
    pub(crate) fn trips(&mut self, backend: &str, last: &Fault) -> Option<String> {
        self.faults_in_a_row += 1;
        (self.faults_in_a_row >= self.max).then(|| {
            format!(
                "not run: {backend} failed {} requests in a row (the last: {}), so its remaining \
                 trials are not run (max_consecutive_faults: {})",
                self.max,
                last.kind(),
                self.max
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn it_trips_on_the_maximum_in_a_row_only() {
        let mut b = Breaker::new(2);
        let fault = Fault::Timeout("late".into());
        assert_eq!(b.trips("x", &fault), None);
        b.answered();
        assert_eq!(b.trips("x", &fault), None);
        let why = b.trips("x", &fault).expect("tripped");
        assert!(
            why.contains("x failed 2 requests in a row (the last: timeout)"),
            "{why}"
        );
    }
}
