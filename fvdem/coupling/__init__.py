"""The coupling bridge (issue 4): closures now; voidage mapping, interpolation and exchange to come."""
