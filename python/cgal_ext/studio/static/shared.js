// What every module of the page shares: the element lookup, the status and error lines, and `studio`, the page's
// state that the browser test reads (window.studio).
export const $ = (id) => document.getElementById(id);

export const studio = {
  n: 0, state: null, geometry: null, rest: null, labels: null, spacing: null,
  labelCodes: { fixed: 0, roi: 1, first_handle: 2 }, maxGroups: 8,
  frameTimes: [], timings: [], errors: [], framesReceived: 0, lastSaved: null,
  busy: false, inFlight: false, pending: null, dragSeq: 0, prepared: null, warnings: null,
};
window.studio = studio;

// Anything the content security policy blocks is a bug of the page's: shown, and the browser test fails on it.
document.addEventListener('securitypolicyviolation', (event) => {
  studio.errors.push(`content security policy: ${event.violatedDirective} blocked ${event.blockedURI}`);
});

export function showError(text) {
  $('error').textContent = text;
  studio.errors.push(text);
}

export function clearError() { $('error').textContent = ''; }

export function status(text) { $('status').textContent = text; }
