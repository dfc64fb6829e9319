"""File formats: one module per kind of file, apart from the types it produces.

File formats: each module reads (and where wirecal writes it, writes) one kind of file,
apart from the types it produces. Every problem is reported as ``file: key: problem`` or
``file:line: problem``.
"""
