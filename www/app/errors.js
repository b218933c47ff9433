// Errors in plain words, for the document controller (document.js) and its
// parts: what a panel's error area shows for any error a job, a check or the
// page itself throws, and the one 'cancelled' error a job left behind meets.
//
//   plainError(err) → a sentence a person can act on, or null (a cancellation)
//   cancelled()     → a JobError of kind 'cancelled' (what the worker pool throws)

/** A sentence a person can act on for any error; null for a cancellation. */
export function plainError(err) {
  if (!err) return null;
  if (err.name === 'JobError' || typeof err.kind === 'string') {
    switch (err.kind) {
      case 'cancelled': return null;
      case 'crash': return 'The computation crashed and its worker was restarted; your work is kept. Try again.';
      case 'protocol': return 'The page and its computation worker disagree (an internal error); your work is kept. Reload the page.';
      default: break;
    }
    const m = String(err.message || '');
    // A request the core could not even read is the page's fault, not the user's.
    if (err.kind === 'bad-request') {
      console.warn('request refused by the core:', m);
      return 'Filigree sent its computation a request it could not read (an internal error); your work is kept. Reload the page.';
    }
    return m;
  }
  if (err instanceof TypeError || err instanceof RangeError || err instanceof ReferenceError || err instanceof SyntaxError) {
    console.error(err);
    return 'Something went wrong inside Filigree (an internal error); your work is kept. Details are in the browser console.';
  }
  return String(err.message || err);
}

/** The error of a request its panel no longer waits for. */
export function cancelled() {
  const e = new Error('cancelled');
  e.name = 'JobError';
  e.kind = 'cancelled';
  return e;
}
