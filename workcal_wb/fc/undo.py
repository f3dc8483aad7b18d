"""One undo step for each change WorkCal makes to a document."""
from contextlib import contextmanager


@contextmanager
def transaction(doc, title: str):
    """One undo step around the block (when the document records undo).  When the block raises, the
    step is aborted and the objects it added are removed, so the document is left as it was, also
    where undo is off (freecadcmd's documents)."""
    opened = bool(getattr(doc, "UndoMode", 0))
    before = {o.Name for o in doc.Objects}
    if opened:
        doc.openTransaction(title)
    try:
        yield
    except BaseException:
        if opened:
            doc.abortTransaction()
        added = [o.Name for o in doc.Objects if o.Name not in before]
        for name in reversed(added):  # the newest first: it may link the older ones
            if doc.getObject(name) is not None:
                doc.removeObject(name)
        raise
    if opened:
        doc.commitTransaction()
