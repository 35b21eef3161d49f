"""What turns an archive into something to read or hand over: typed report views, the
HTML report, figures, exports and the generated case documentation."""
