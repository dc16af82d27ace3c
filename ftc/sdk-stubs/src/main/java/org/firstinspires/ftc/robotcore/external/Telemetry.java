// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package org.firstinspires.ftc.robotcore.external;

/**
 * Stub: the data/line/update subset of Telemetry, plus the Func producer, log and display format used by
 * official samples (no actions or speech). Those additions are default methods that throw, so motorlab's
 * simulated Telemetry need not implement them; in the SDK they are abstract.
 */
public interface Telemetry {
    Item addData(String caption, String format, Object... args);

    Item addData(String caption, Object value);

    /** An item whose value is formatted from valueProducer each time telemetry is sent. */
    default <T> Item addData(String caption, String format, Func<T> valueProducer) {
        throw new UnsupportedOperationException("stub");
    }

    void clear();

    void clearAll();

    boolean update();

    Line addLine();

    Line addLine(String lineCaption);

    boolean isAutoClear();

    void setAutoClear(boolean autoClear);

    int getMsTransmissionInterval();

    void setMsTransmissionInterval(int msTransmissionInterval);

    /** How the Driver Station renders the telemetry text. */
    default void setDisplayFormat(DisplayFormat displayFormat) {
        throw new UnsupportedOperationException("stub");
    }

    /** The append-only message log shown below the items. */
    default Log log() {
        throw new UnsupportedOperationException("stub");
    }

    enum DisplayFormat { CLASSIC, MONOSPACE, HTML }

    /** Stub: the subset of Telemetry.Log used by ConceptTelemetry. */
    interface Log {
        enum DisplayOrder { NEWEST_FIRST, OLDEST_FIRST }

        void setCapacity(int capacity);

        void setDisplayOrder(DisplayOrder displayOrder);

        void add(String entry);
    }

    interface Line {
        Item addData(String caption, String format, Object... args);

        Item addData(String caption, Object value);
    }

    interface Item {
        String getCaption();

        Item setCaption(String caption);

        Item setValue(String format, Object... args);

        Item setValue(Object value);

        Item setRetained(Boolean retained);

        boolean isRetained();

        Item addData(String caption, String format, Object... args);

        Item addData(String caption, Object value);
    }
}
