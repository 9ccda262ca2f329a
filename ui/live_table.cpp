#include "ui/live_table.h"

#include <QBrush>
#include <QColor>
#include <QHeaderView>
#include <QTableWidget>
#include <algorithm>

namespace lumistage {

void makeLiveTable(QTableWidget& table, int stretched) {
  QHeaderView* header = table.horizontalHeader();
  header->setSectionResizeMode(QHeaderView::Interactive);
  if (stretched >= 0) header->setSectionResizeMode(stretched, QHeaderView::Stretch);
  fitLiveColumns(table);
}

void setLiveCell(QTableWidget& table, int row, int column, const QString& text) {
  if (QTableWidgetItem* item = table.item(row, column)) {
    item->setText(text);  // Qt tells the view only when the text changed
  } else {
    table.setItem(row, column, new QTableWidgetItem(text));
  }
}

void setLiveCell(QTableWidget& table, int row, int column, const QString& text,
                 const QColor& colour) {
  setLiveCell(table, row, column, text);
  table.item(row, column)->setForeground(colour);  // likewise
}

void fitLiveColumns(QTableWidget& table) {
  QHeaderView* header = table.horizontalHeader();
  // sizeHintForColumn is public in QAbstractItemView (QTableView overrides it protected).
  const QAbstractItemView& view = table;
  for (int c = 0; c < table.columnCount(); ++c) {
    if (header->isSectionHidden(c) || header->sectionResizeMode(c) != QHeaderView::Interactive)
      continue;
    if (header->stretchLastSection() && header->visualIndex(c) == header->count() - 1) continue;
    const int wanted = std::max(view.sizeHintForColumn(c), header->sectionSizeHint(c));
    if (wanted != header->sectionSize(c)) header->resizeSection(c, wanted);
  }
}

}  // namespace lumistage
