"""Files the app writes are whole or not there: a recording is checked (its Rerun footer, the bag closed) before
it replaces anything, and a write that failed is named with its cause ("no space left on device")."""
