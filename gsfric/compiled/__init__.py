"""The generated model at run time: the manifest of generated/ and its functions compiled on
first use (``native``), with the batch driver (``batch.c``)."""
