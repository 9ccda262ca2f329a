#pragma once

#include <QString>

class QColor;
class QTableWidget;

namespace lumistage {

// Tables that a panel rewrites several times a second (camera health, the pipeline's nodes).
// Under QHeaderView::ResizeToContents every cell that changes makes the view measure every cell of
// every column again, before the next one changes: the pipeline panel's table took 46% of the
// studio's GUI thread in the demo. A live table keeps its columns Interactive (a stretched one
// stays stretched), rewrites only the cells whose text changed, and fits its columns to their
// contents once an update (fitLiveColumns), as ResizeToContents would.

// Makes `table`'s columns Interactive and fitted to their contents, except `stretched` (-1: none).
void makeLiveTable(QTableWidget& table, int stretched = -1);

// The cell's text (its item made when missing); nothing happens when it is already `text`.
void setLiveCell(QTableWidget& table, int row, int column, const QString& text);
// The same with the text's colour.
void setLiveCell(QTableWidget& table, int row, int column, const QString& text,
                 const QColor& colour);

// Sizes each Interactive column (not the stretched last one) to its contents or its header.
void fitLiveColumns(QTableWidget& table);

}  // namespace lumistage
