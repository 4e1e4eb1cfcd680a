#include "flow_layout.h"

#include <QWidget>

#include <algorithm>

namespace burnish::studio {

FlowLayout::FlowLayout(QWidget* parent, int horizontalSpacing, int verticalSpacing)
    : QLayout(parent)
    , m_hSpacing(horizontalSpacing)
    , m_vSpacing(verticalSpacing) {}

FlowLayout::~FlowLayout() {
    while (QLayoutItem* item = takeAt(0))
        delete item;
}

void FlowLayout::addItem(QLayoutItem* item) {
    m_items.append(item);
}

int FlowLayout::count() const {
    return int(m_items.size());
}

QLayoutItem* FlowLayout::itemAt(int index) const {
    return index >= 0 && index < m_items.size() ? m_items[index] : nullptr;
}

QLayoutItem* FlowLayout::takeAt(int index) {
    return index >= 0 && index < m_items.size() ? m_items.takeAt(index) : nullptr;
}

Qt::Orientations FlowLayout::expandingDirections() const {
    return {};
}

bool FlowLayout::hasHeightForWidth() const {
    return true;
}

int FlowLayout::heightForWidth(int width) const {
    return arrange(QRect(0, 0, width, 0), false);
}

QSize FlowLayout::minimumSize() const {
    // As narrow as the widest item: everything else wraps.
    QSize size;
    for (const QLayoutItem* item : m_items)
        if (!item->isEmpty()) size = size.expandedTo(item->minimumSize());
    const QMargins m = contentsMargins();
    return size + QSize(m.left() + m.right(), m.top() + m.bottom());
}

QSize FlowLayout::sizeHint() const {
    // Every item on one row.
    int width = 0, height = 0, visible = 0;
    for (const QLayoutItem* item : m_items) {
        if (item->isEmpty()) continue;
        width += item->sizeHint().width();
        height = std::max(height, item->sizeHint().height());
        ++visible;
    }
    width += std::max(0, visible - 1) * m_hSpacing;
    const QMargins m = contentsMargins();
    return {width + m.left() + m.right(), height + m.top() + m.bottom()};
}

void FlowLayout::setGeometry(const QRect& rect) {
    QLayout::setGeometry(rect);
    arrange(rect, true);
}

int FlowLayout::arrange(const QRect& rect, bool apply) const {
    const QMargins m = contentsMargins();
    const QRect area = rect.adjusted(m.left(), m.top(), -m.right(), -m.bottom());
    // Rows first, so each row's items can share its spare width and be centred vertically.
    struct Row {
        int first = 0, last = 0, width = 0, height = 0;
    };
    QList<Row> rows;
    Row row;
    for (int i = 0; i < m_items.size(); ++i) {
        const QLayoutItem* item = m_items[i];
        if (item->isEmpty()) continue;
        const QSize hint = item->sizeHint();
        const int w = std::min(hint.width(), area.width());
        if (row.last > row.first && row.width + m_hSpacing + w > area.width()) {
            rows.append(row);
            row = Row{i, i, 0, 0};
        }
        if (row.last == row.first) row.first = i;
        row.width += (row.last > row.first ? m_hSpacing : 0) + w;
        row.height = std::max(row.height, hint.height());
        row.last = i + 1;
    }
    if (row.last > row.first) rows.append(row);

    int y = area.y();
    for (const Row& r : rows) {
        if (apply) {
            // Items that ask to grow (sliders) share the row's spare width.
            int growing = 0;
            for (int i = r.first; i < r.last; ++i)
                if (!m_items[i]->isEmpty() && (m_items[i]->expandingDirections() & Qt::Horizontal)) ++growing;
            const int spare = std::max(0, area.width() - r.width);
            int x = area.x();
            for (int i = r.first; i < r.last; ++i) {
                QLayoutItem* item = m_items[i];
                if (item->isEmpty()) continue;
                const QSize hint = item->sizeHint();
                int w = std::min(hint.width(), area.width());
                if (growing > 0 && (item->expandingDirections() & Qt::Horizontal)) w += spare / growing;
                item->setGeometry(QRect(x, y + (r.height - hint.height()) / 2, w, hint.height()));
                x += w + m_hSpacing;
            }
        }
        y += r.height + m_vSpacing;
    }
    if (!rows.isEmpty()) y -= m_vSpacing;
    return y - area.y() + m.top() + m.bottom();
}

} // namespace burnish::studio
