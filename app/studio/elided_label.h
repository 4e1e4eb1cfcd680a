#pragma once
// A one-line label that never widens its window: text longer than the space it is given ends in
// "…", and the whole text is in its tooltip. For status texts that grow (a texture header, the
// shimmer meter, a file path).
#include <QFrame>
#include <QString>

namespace burnish::studio {

class ElidedLabel : public QFrame {
    Q_OBJECT
public:
    explicit ElidedLabel(QWidget* parent = nullptr);
    explicit ElidedLabel(const QString& text, QWidget* parent = nullptr);

    void setText(const QString& text);
    const QString& text() const { return m_text; }
    /// The text as drawn at the current width ("…" where it was cut).
    QString shownText() const;

    QSize sizeHint() const override;
    QSize minimumSizeHint() const override;

protected:
    void paintEvent(QPaintEvent* event) override;

private:
    QString m_text;
};

} // namespace burnish::studio
