// A promise that gives up: storage, the clipboard and other browser calls
// that may never answer in some hosts.

/** `promise`, or a rejection once `ms` have passed. */
export function withTimeout(promise, ms, what) {
  let timer;
  return Promise.race([
    promise,
    new Promise((_, reject) => { timer = setTimeout(() => reject(new Error(`${what} did not answer within ${ms} ms`)), ms); }),
  ]).finally(() => clearTimeout(timer));
}
