"""Reading and writing the SSL league's log file format (ssl-go-tools pkg/persistence)."""
